// Techniques: each integrator (path, light, bdpt, vcm, bpm, sppm) is one host object, registered once.
// It names its kernel and entry point, its -D flags, the film layers it writes, how its units cover the
// film, which render options apply to it and how its film becomes an image. The render loop
// (runtime/renderer.cpp), the OpenCL worker (runtime/device_worker.cpp), checkpoints and the command line
// know techniques only through this. A new integrator is its kernel file, its technique file
// (runtime/technique_*.cpp) and one line in technique.cpp's registry.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "runtime/film_layout.h"  // and kernels/shared/types.h
#include "kernels/shared/light_types.h"

struct DeviceInfo;
struct DeviceScene;
struct Film;
struct LightTransportSetup;
struct RenderOptions;

// How a technique's units cover the film (runtime/render_schedule.h schedules both the same way: tiles of
// indices at levels of samples).
enum class UnitKind {
  pixels,  // a unit is samples [s0, s1) of a run of pixels, added in order to their ordered layers
  paths,   // a unit is samples [s0, s1) of a run of light-path indices (numbered like the pixels), whose
           // splats land anywhere: the unit returns its commutative layers over the whole image
};

// What a technique's build_options sees.
struct TechniqueBuild {
  const DeviceInfo* device = nullptr;
  uint32_t lanes = 1;          // the width the kernel is built for (techniques with `lanes`)
  uint32_t max_depth = 0;
  bool splat_pairs = false;    // 32-bit word pairs even where 64-bit atomics exist (tests)
};

// One launch of a unit: a kernel of the technique's file and its arguments after PC_SCENE_PARAMS, by name:
//   "film"          the film buffer (the technique's layers first, at word 0; then the AOVs)
//   "stats"         UnitStats, cleared before the unit's first phase (SplatStats's words for splats)
//   "lt", "emission_cdf"  the light-transport header and emission distribution (techniques with emission)
//   a name of one of the technique's buffers (Technique::buffers)
//   "unit"          the unit's range: uint begin, uint count, [uint stride (pixel units only),]
//                   uint sample_begin, uint sample_count
// A phase runs ceil(count / P) work items for a unit of `count` pixels or paths (P: 1, or the lane kernels'
// pixels per work item, PC_ITEM_PIXELS), or as many as its `items` says: a phase over something else than the unit's
// pixels (a photon grid's cells, one work item for a serial scan, two per pixel) gets the unit's range
// all the same and finds its own work from it. Phases run in order; each is timed and named in --stats.
// A phase's kernel must do nothing for a unit of count 0: the worker launches each so once at set-up.
struct TechniquePhase {
  std::string name;  // "render"
  std::string entry;
  std::vector<std::string> args;
  // Work items for a unit of `count` pixels or paths in a film of `pixels`, P of them a work item with lanes;
  // empty: ceil(count / P).
  std::function<size_t(uint32_t count, uint32_t pixels, uint32_t item_pixels)> items;
};

// What a technique's buffers and its largest unit depend on: the film, the render's depth, the device.
struct TechniqueSizes {
  uint32_t pixels = 0;      // the film's
  uint32_t max_depth = 0;
  uint32_t unit_items = 0;  // the largest unit's pixels or paths on this device (Technique::max_unit_items)
  const DeviceInfo* device = nullptr;
  uint32_t light_paths = 0;  // LightTransportHeader.light_paths (the gathering integrators' per iteration)
  uint32_t prims = 0;        // the scene's primitives (SceneHeader.prim_count)
  uint32_t bootstrap = 0;    // LightTransportHeader.bootstrap (mlt's bootstrap states per depth)
};

// A device buffer of the technique's own, made at set-up, cleared to zero once, and kept for the whole
// render: what one phase leaves for the next, or for the next unit (a photon map's grid).
struct TechniqueBuffer {
  std::string name;
  std::function<size_t(const TechniqueSizes&)> bytes;
};

// An option of the technique's own, set in the scene file as render.integrator's key (`{"type": "path",
// "lanes": 8}`): a number the technique checks and stores into the render's options.
struct TechniqueOption {
  std::string name;
  std::string expected;  // for messages: "1, 8 or 16"
  std::function<bool(double value, RenderOptions& options)> set;  // false: not an expected value
};

// Options of the usual kinds, each stored into a field of RenderOptions: `true` or `false` (flag_option), a
// whole number from 1 to `most` (count_option: "a whole number of WHAT, 1 to MOST"), a number that `fits`
// (number_option, `expected` saying which).
// The `lanes` option of the techniques that run over SIMD lanes (Technique::lanes; `what` runs in each lane),
// and the -D flag of the width a program is built for.
TechniqueOption lanes_option(const std::string& what);
std::string lanes_build_option(const TechniqueBuild& build);
TechniqueOption flag_option(const std::string& name, bool RenderOptions::*field);
TechniqueOption count_option(const std::string& name, const std::string& what, uint32_t most, uint32_t RenderOptions::*field);
TechniqueOption number_option(const std::string& name, const std::string& expected, std::function<bool(double)> fits,
                              double RenderOptions::*field);

struct Technique {
  std::string name;     // as --integrator and render.integrator take it
  uint32_t id = 0;      // stored in checkpoints and hashed into render keys (path 0, light 1, bdpt 2, vcm 3, bpm 4,
                        // sppm 5, instant_radiosity 6, radiosity 7, mlt 8); never reused
  std::string summary;  // one line for --help and the docs
  std::string kernel_file;             // its program's main file under kernels/
  std::vector<TechniquePhase> phases;  // what a unit runs
  std::vector<TechniqueBuffer> buffers;
  std::vector<FilmLayer> layers;  // its own film layers
  // Where a layer's size depends on the render's max_depth (mlt's chain states): its layers for a depth, the
  // same names as `layers`; may be empty.
  std::function<std::vector<FilmLayer>(uint32_t max_depth)> layers_at_depth;
  UnitKind units = UnitKind::pixels;
  bool lanes = false;        // runs over 8 or 16 SIMD lanes on CPU devices (--lanes)
  uint32_t max_depth_limit = 1024;  // largest max_depth it takes
  // Its phases run once per sample of a unit, in sample order (sample_count 1 each time), instead of once
  // over the unit's samples: an iteration's phases (trace light paths, build a grid over their vertices,
  // gather) finish before the next iteration's begin.
  bool per_sample = false;
  // The largest unit (pixels or paths) a device takes, when the technique's buffers grow with it (light
  // subpaths kept per path): sizes.unit_items is 0 here. Empty: any. Units never exceed it (the schedule
  // takes the smallest over the devices), so an iteration too large for a device is split into units.
  std::function<uint32_t(const TechniqueSizes&)> max_unit_items;
  double cpu_unit_seconds = 0.25;   // unit duration to aim for on CPU devices
  std::vector<TechniqueOption> options;
  // Its options' values, hashed into render keys (checkpoints resume only the same settings); may be empty.
  std::function<std::vector<double>(const RenderOptions&)> key_settings;
  // Fills the light-transport header's fields of its own from the render's options (techniques with
  // emission); may be empty.
  std::function<void(LightTransportSetup& setup, const DeviceScene& scene, const RenderOptions& options)> setup_light;
  // Checks that it can render the scene (UsageError naming what it does not take) and returns warnings of
  // what it approximates; may be empty.
  std::function<std::vector<std::string>(const DeviceScene& scene)> check_scene;
  // Extra -D flags for a device (besides the scene's features); may be empty.
  std::function<std::string(const TechniqueBuild&)> build_options;
  // The film's image: fills film.mean, variance, even_mean and odd_mean from the technique's layers at
  // film.spp (the schedule's level); counts fixed-point sums that reached 2^63 in *overflows.
  std::function<void(Film& film, const LightTransportHeader& lt, uint64_t* overflows)> develop;
};

// Every registered technique, in registration order (path, light, bdpt, vcm, bpm, sppm, instant_radiosity,
// radiosity, mlt, then any a test adds).
const std::vector<Technique>& techniques();
// Adds one (tests: a technique of their own, with a kernel from register_kernel_source); the name and id
// must be new.
void register_technique(Technique technique);
// The technique of this name; UsageError "WHERE: unknown integrator "NAME" (expected path, light, ...)".
const Technique& technique_named(const std::string& name, const std::string& where);
// Whether a phase takes "lt" or "emission_cdf": the render then sets up the emission distribution and the
// splat scales (runtime/light_transport.h).
bool uses_emission(const Technique& t);
// The largest unit a device takes (Technique::max_unit_items), at least 1, at most the film's pixels.
uint32_t technique_unit_items(const Technique& t, TechniqueSizes sizes);
// Its film layers for a render of this max_depth (Technique::layers, or layers_at_depth's).
std::vector<FilmLayer> technique_layers(const Technique& t, uint32_t max_depth);
// By id (checkpoints); nullptr if none has it.
const Technique* technique_with_id(uint32_t id);
// "path, light, bdpt, vcm, bpm, sppm, instant_radiosity, radiosity or mlt"
std::string technique_list();

// Refuses options that do not apply to the technique or exceed its limits (UsageError naming them).
void check_technique_options(const Technique& t, const RenderOptions& options);
// Sets the technique's own options from a JSON object's text (SceneDescription's integrator_options); an
// unknown key or a bad value is a UsageError naming its place ("scene.json: render.integrator.lanes: ...").
void apply_technique_options(const Technique& t, const std::string& json_object, const std::string& place,
                             RenderOptions& options);

// The registry's lines (runtime/technique_*.cpp).
Technique path_technique();
Technique light_technique();
Technique bdpt_technique();
Technique vcm_technique();
Technique bpm_technique();
Technique sppm_technique();
Technique instant_radiosity_technique();
Technique radiosity_technique();
Technique mlt_technique();
