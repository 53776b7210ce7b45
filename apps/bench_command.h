// `pathcl bench [--device SEL[,SEL...]|all] [--suite quick|standard] [--json FILE] [--check]`: the
// OpenCL device benchmark (runtime/bench.h). Prints a table per device, and with several devices
// their results together; --json writes every figure.
#pragma once
#include <string>

namespace CLI {
class App;
}

void add_bench_command(CLI::App& app);
bool bench_command_parsed();
// Exit code: 0, 1 with --check when a device failed the gate, 130/143 when interrupted.
int run_bench_command(const std::string& pathcl_version);
