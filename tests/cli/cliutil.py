"""Shared by the CLI tests (tests/cli/test_*.py): the pass/fail tally and the closing summary line.
Each test script imports it (its own folder is first on sys.path) and ends with finish()."""
import sys

passed = failed = 0


def check(name, ok, detail=""):
    """Counts one check; a failure prints its name and (the start of) the detail."""
    global passed, failed
    if ok:
        passed += 1
    else:
        failed += 1
        print("FAIL:", name, str(detail)[:2000])
    return ok


def finish():
    """Prints 'N passed, N failed' (the suite's summary format) and returns the exit code."""
    print("%d passed, %d failed" % (passed, failed))
    sys.stdout.flush()
    return 1 if failed else 0
