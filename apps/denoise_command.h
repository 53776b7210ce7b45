// `pathcl denoise IN.exr -o OUT.exr [--no-aux] [--quality high|balanced|fast]`: denoises an EXR image
// with Intel Open Image Denoise (runtime/denoise.h), using its layers "albedo" (R, G, B) and "normal"
// (X, Y, Z) where present. OUT holds the denoised R, G, B, the input beauty as the layer "raw", the
// input's other layers, variance and attributes, and the attributes "denoiser", "denoiser_quality" and
// "denoiser_aux".
#pragma once

namespace CLI {
class App;
}

// Registers the `denoise` subcommand on app; its arguments are kept until run_denoise_command().
void add_denoise_command(CLI::App& app);
// Whether the command line chose `denoise` (after app.parse()).
bool denoise_command_parsed();
// Checks the output, reads IN, denoises and writes OUT; returns the exit code (0). Bad usage or input
// throws UsageError (exit 2), a missing library or a failing write RuntimeFailure (exit 1).
int run_denoise_command();
