// The hawor subcommands; each is a thin main over include/hawor.
#pragma once

namespace hawor_cli {
int cmdMetrics(int argc, char** argv);  // hawor metrics camera|hands ...
int cmdDemo(int argc, char** argv);     // hawor demo --out DIR
}  // namespace hawor_cli
