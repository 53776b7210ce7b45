// `pathcl compare REFERENCE TEST [--mask FILE] [--json] [--z-threshold X]`: error metrics of an EXR
// image against a reference EXR (see runtime/image_compare.h).
#pragma once

namespace CLI {
class App;
}

// Registers the `compare` subcommand on app; its arguments are kept until run_compare_command().
void add_compare_command(CLI::App& app);
// Whether the command line chose `compare` (after app.parse()).
bool compare_command_parsed();
// Reads the images, prints the metrics to stdout and returns the exit code (0). Bad input (an
// unreadable file, sizes that differ, non-finite pixels) throws UsageError, which main() maps to 2.
int run_compare_command();
