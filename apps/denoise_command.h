// `pathcl denoise IN.exr -o OUT.exr [--aux albedo,normal|albedo|none] [--no-aux] [--quality high|balanced|fast]`:
// denoises an EXR image with Intel Open Image Denoise (runtime/denoise.h, denoise_image), guided by its layers
// "albedo" (R, G, B) and "normal" (X, Y, Z) unless --aux or --no-aux (= --aux none) asks for fewer; a guide
// asked for and missing is an error (exit 2). OUT holds the denoised R, G, B, the input beauty as the layer
// "raw" (an input denoised before is denoised again from its raw layer, which is kept), the variance as the
// layer "raw.variance", the input's other layers and attributes ("determinism" as "raw.determinism"), and
// the attributes "determinism" (kDenoisedDeterminism), "denoiser", "denoiser_device", "denoiser_quality" and
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
