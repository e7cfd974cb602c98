"""Cross-check of hawor's .npy / .npz I/O against numpy (driven by tests/io/ref_numpy.cpp).

  io_numpy.py <out.txt> make <dir>
      numpy writes its arrays with np.save (np_<name>.npy), np.savez (np_stored.npz),
      np.savez_compressed (np_compressed.npz) and format versions 2.0 / 3.0 (np_v2.npy,
      np_v3.npy). <out.txt> receives, per array, its values as float64 (C order), its dtype string
      and its header's fortran_order flag, plus the list of names (strings as character codes).
  io_numpy.py <out.txt> check <dir>
      numpy loads what hawor wrote (cpp_<name>.npy, cpp_stored.npz, cpp_compressed.npz,
      cpp_zip64.npz) and compares dtype (byte order included), shape, fortran_order and every
      element byte with its own arrays. <out.txt> receives the number of files checked and of
      failures; each failure is described on stderr.

The arrays are generated here from a fixed seed, so both modes see the same data.
"""
import os
import sys
import zipfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import refio  # noqa: E402


def arrays():
    rng = np.random.default_rng(20240611)
    a = {}
    f8 = rng.standard_normal((3, 4))
    f8[0, :4] = [np.nan, np.inf, -0.0, -np.inf]
    f8[1, 0] = 5e-324  # smallest subnormal
    a["f8_c"] = f8
    a["f4_c"] = rng.standard_normal((2, 3, 4)).astype(np.float32)
    a["f8_f"] = np.asfortranarray(rng.standard_normal((3, 5)))
    a["f4_f"] = np.asfortranarray(rng.standard_normal((2, 3, 4)).astype(np.float32))
    a["f8_be"] = rng.standard_normal(5).astype(">f8")
    a["f4_be_f"] = np.asfortranarray(rng.standard_normal((4, 3)).astype(">f4"))
    a["i4_be_f"] = np.asfortranarray(rng.integers(-2**31, 2**31, (2, 3)).astype(">i4"))
    a["i1"] = np.array([-128, 127, 0, -1, 5], dtype=np.int8)
    a["i2"] = rng.integers(-2**15, 2**15, (4, 2)).astype(np.int16)
    a["i4"] = np.array([-2**31, 2**31 - 1, 0, 42], dtype=np.int32)
    # int64 / uint64 extremes that float64 holds exactly (the values travel as float64 text).
    a["i8"] = np.array([-2**63, 2**62, -(2**53), 2**53 + 2, 0, -1], dtype=np.int64)
    a["u1"] = np.array([0, 255, 128], dtype=np.uint8)
    a["u2_be"] = np.array([0, 65535, 258], dtype=">u2")
    a["u4"] = np.array([0, 2**32 - 1, 7], dtype=np.uint32)
    a["u8"] = np.array([0, 2**63, 2**64 - 2048, 12345], dtype=np.uint64)
    a["b1"] = rng.random((3, 3)) > 0.5
    a["b1_f"] = np.asfortranarray(rng.random((2, 5)) > 0.5)
    a["f2"] = np.array([1, -2, 65504, 6e-8, np.inf, 0.333, -0.0], dtype=np.float16)
    a["f8_0d"] = np.array(3.5)
    a["i8_0d"] = np.array(-7, dtype=np.int64)
    a["f8_empty"] = np.zeros((0,))
    a["i4_empty"] = np.zeros((2, 0, 3), dtype=np.int32)
    a["b1_empty"] = np.zeros((0,), dtype=bool)
    a["big"] = np.tile(np.arange(37.0), (100, 1))  # compressible
    return a


def fortran_flag(arr):
    return bool(np.lib.format.header_data_from_array_1_0(arr)["fortran_order"])


def codes(s):
    return [ord(c) for c in s]


def header_of(path):
    with open(path, "rb") as f:
        version = np.lib.format.read_magic(f)
        if version == (1, 0):
            return np.lib.format.read_array_header_1_0(f)
        return np.lib.format.read_array_header_2_0(f)


def make(out, d):
    os.makedirs(d, exist_ok=True)
    a = arrays()
    for name, arr in a.items():
        np.save(os.path.join(d, "np_%s.npy" % name), arr)
    np.savez(os.path.join(d, "np_stored.npz"), **a)
    np.savez_compressed(os.path.join(d, "np_compressed.npz"), **a)
    for v in (2, 3):
        with open(os.path.join(d, "np_v%d.npy" % v), "wb") as f:
            np.lib.format.write_array(f, a["f8_f"], version=(v, 0))
    res = {"names": codes(",".join(a))}
    for name, arr in a.items():
        res[name] = arr.astype(np.float64)
        res["dtype_" + name] = codes(arr.dtype.str)
        res["fortran_" + name] = [1.0 if fortran_flag(arr) else 0.0]
    refio.save(out, **res)


def same(expect, got, what, failures):
    if got.dtype != expect.dtype or got.dtype.str != expect.dtype.str:
        failures.append("%s: dtype %s, expected %s" % (what, got.dtype.str, expect.dtype.str))
    elif got.shape != expect.shape:
        failures.append("%s: shape %s, expected %s" % (what, got.shape, expect.shape))
    elif got.tobytes(order="C") != expect.tobytes(order="C"):
        failures.append("%s: element bytes differ" % what)


def check(out, d):
    a = arrays()
    failures = []
    checked = 0
    for name, arr in a.items():
        path = os.path.join(d, "cpp_%s.npy" % name)
        if not os.path.exists(path):
            continue
        checked += 1
        try:
            shape, fortran, dtype = header_of(path)
            if fortran != fortran_flag(arr):
                failures.append("%s: fortran_order %s" % (path, fortran))
            same(arr, np.load(path), path, failures)
        except Exception as e:  # report, do not crash: the C++ test prints the count
            failures.append("%s: numpy failed to load: %r" % (path, e))
    written = [n for n in a if os.path.exists(os.path.join(d, "cpp_%s.npy" % n))]
    for fname, method in (("cpp_stored.npz", zipfile.ZIP_STORED),
                          ("cpp_compressed.npz", zipfile.ZIP_DEFLATED),
                          ("cpp_zip64.npz", zipfile.ZIP_DEFLATED)):
        path = os.path.join(d, fname)
        checked += 1
        try:
            with zipfile.ZipFile(path) as zf:
                bad = zf.testzip()  # reads every member, verifies CRC-32
                if bad is not None:
                    failures.append("%s: CRC error in %s" % (path, bad))
                infos = zf.infolist()
                if [i.filename for i in infos] != [n + ".npy" for n in written]:
                    failures.append("%s: members %s" % (path, [i.filename for i in infos]))
                if infos and infos[-1].compress_type != method:  # 'big' compresses
                    failures.append("%s: compress_type %d" % (path, infos[-1].compress_type))
            with np.load(path) as z:
                if sorted(z.files) != sorted(written):
                    failures.append("%s: keys %s" % (path, z.files))
                for n in written:
                    got = z[n]
                    same(a[n], got, "%s[%s]" % (path, n), failures)
                    f = bool(got.flags.f_contiguous and not got.flags.c_contiguous)
                    if f != fortran_flag(a[n]):
                        failures.append("%s[%s]: memory order" % (path, n))
        except Exception as e:
            failures.append("%s: numpy failed to load: %r" % (path, e))
    for f in failures:
        print("io_numpy check: " + f, file=sys.stderr)
    refio.save(out, checked=[checked], failures=[len(failures)])


if __name__ == "__main__":
    out, mode, d = sys.argv[1], sys.argv[2], sys.argv[3]
    {"make": make, "check": check}[mode](out, d)
