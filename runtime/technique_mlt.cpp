// Metropolis light transport in primary sample space over BDPT's strategies (kernels/mlt.cl): a chain per
// pixel index, its state in the film's ordered "chains" layer, its splats in the commutative "splats" and
// "large" layers, the pixels' own samples of depths 0 and 1 in "independent".
#include <algorithm>
#include <cmath>
#include <cstring>

#include "runtime/device.h"
#include "runtime/film.h"
#include "runtime/light_transport.h"
#include "runtime/renderer.h"
#include "runtime/technique.h"
#include "scene/device_scene.h"

namespace {

// kernels/mlt.cl's PC_MLT_HEADER_WORDS, PC_MLT_BOOTSTRAP_ITEMS and PC_MLT_MAX_DEPTH.
constexpr uint32_t kHeaderWords = 16;
constexpr size_t kBootstrapItems = 4096;
// kernels/mlt.cl's mlt_bootstrap_items: the bootstrap's work items for a film of `pixels`.
size_t bootstrap_items(uint32_t pixels) { return std::min<size_t>(kBootstrapItems, pixels); }
constexpr uint32_t kMaxDepth = 16;

// A chain's state: its header, and 4 numbers and the iteration of their last change for each of the 4 D + 4
// groups a BDPT sample of depth D reads.
uint32_t state_words(uint32_t max_depth) { return kHeaderWords + 5 * (4 * max_depth + 4); }

// The chains' states, the Metropolis samples' splats, the pixels' own samples of depths 0 and 1 (halves: even
// and odd steps) and the large steps' splats (halves, as the Metropolis samples': the first and the second
// half of the chains; kernels/mlt.cl).
std::vector<FilmLayer> mlt_layers(uint32_t max_depth) {
  return {{"chains", PC_LAYER_ORDERED, state_words(max_depth)},
          {"splats", PC_LAYER_COMMUTATIVE, 2 * PC_SPLAT_WORDS},
          {"independent", PC_LAYER_COMMUTATIVE, 2 * PC_SPLAT_WORDS},
          {"large", PC_LAYER_COMMUTATIVE, 2 * PC_SPLAT_WORDS}};
}

}  // namespace

Technique mlt_technique() {
  Technique t;
  t.name = "mlt";
  t.id = PC_INTEGRATOR_MLT;
  t.summary = "Metropolis light transport in primary sample space over BDPT's strategies (multiplexed)";
  t.kernel_file = "mlt.cl";
  t.layers = mlt_layers(8);
  t.layers_at_depth = mlt_layers;
  t.units = UnitKind::pixels;
  t.max_depth_limit = kMaxDepth;
  t.cpu_unit_seconds = 1.0;
  const std::vector<std::string> scan = {"lt", "bootstrap", "unit"};
  t.phases = {
      {"bootstrap", "mlt_bootstrap", {"lt", "emission_cdf", "stats", "light_vertices", "bootstrap", "unit"},
       [](uint32_t, uint32_t pixels, uint32_t) { return bootstrap_items(pixels); }},
      {"scan", "mlt_scan_blocks", scan, [](uint32_t, uint32_t, uint32_t) { return size_t(PC_SCAN_BLOCKS); }},
      {"scan_offsets", "mlt_scan_offsets", scan, [](uint32_t, uint32_t, uint32_t) { return size_t(1); }},
      {"scan_add", "mlt_scan_add", scan, [](uint32_t, uint32_t, uint32_t) { return size_t(PC_SCAN_BLOCKS); }},
      {"bootstrap_done", "mlt_bootstrap_done", scan, [](uint32_t, uint32_t, uint32_t) { return size_t(1); }},
      {"chains", "mlt_chains", {"lt", "emission_cdf", "film", "stats", "light_vertices", "bootstrap", "unit"}, {}},
  };
  // Light vertex slots for each chain of the largest unit, or each bootstrap work item; the candidates'
  // importances (B per depth 2 .. D), the prefix sum's total and block offsets (kernels/scan.cl), the done mark.
  t.buffers = {{"light_vertices", [](const TechniqueSizes& s) {
                  return std::max<size_t>(s.unit_items, bootstrap_items(s.pixels)) * light_vertex_slots(s) * sizeof(LightVertex);
                }},
               {"bootstrap", [](const TechniqueSizes& s) {
                  return (size_t(s.bootstrap) * s.max_depth + 1 + PC_SCAN_BLOCKS + 1) * sizeof(float);
                }}};
  t.max_unit_items = [](const TechniqueSizes& s) { return light_vertex_unit_paths(s, 0); };
  t.build_options = splat_build_options;
  t.options = {count_option("bootstrap", "bootstrap states per depth", 1u << 20, &RenderOptions::bootstrap),
               number_option("large_step", "a probability in [0, 1]", [](double v) { return v >= 0 && v <= 1; },
                             &RenderOptions::large_step),
               number_option("mutation_size", "a number in (0, 1] (the largest move of a small step)",
                             [](double v) { return v > 0 && v <= 1; }, &RenderOptions::mutation_size)};
  t.key_settings = [](const RenderOptions& o) {
    return std::vector<double>{double(o.bootstrap), o.large_step, o.mutation_size};
  };
  t.setup_light = [](LightTransportSetup& setup, const DeviceScene&, const RenderOptions& o) {
    LightTransportHeader& lt = setup.header;
    lt.bootstrap = o.bootstrap;
    lt.large_step = float(o.large_step);
    lt.mutation_size = float(o.mutation_size);
    // The splats are in pixel values (their weights take b0): light tracing's fixed-point scales.
  };
  // The pixels' own samples and the large steps' splats, plus the Metropolis splats times b / b0
  // (kernels/mlt.cl): b0 the bootstrap's estimate of b, the image's mean luminance beyond depth 1, which their
  // weights take (chain header word 1: the candidates' importance sum, over B); b from the candidates and every
  // chain's large-step proposals (words 9-11: their count and importance sum), summed in chain order, each an
  // independent uniform state of mean b / (D - 1).
  // The error: the chains' splats go to the half of their set of chains, so each half image is an independent
  // estimate, and their difference measures the chains' error (the relMSE estimate, --target-error and the
  // variance). A chain's even and odd steps are nearly the same paths: as halves they made the estimate 5 to
  // 900 times too low (docs/light-transport.md). The pixels' own samples are independent from step to step.
  t.develop = [](Film& film, const LightTransportHeader& lt, uint64_t* overflows) {
    // The first half's share of the chains: kernels/mlt.cl's chain_half puts chains c with 2 c < pixels there.
    const double first_share = std::ceil(film.layout.pixels / 2.0) / std::max<uint32_t>(film.layout.pixels, 1);
    struct Developed {
      std::vector<float> mean, variance, even_mean, odd_mean;
    };
    auto developed = [&film] { return Developed{film.mean, film.variance, film.even_mean, film.odd_mean}; };
    develop_splat_layer(film, lt, overflows, "independent");
    const Developed own = developed();
    develop_splat_layer(film, lt, overflows, "large", first_share);
    const Developed large = developed();
    develop_splat_layer(film, lt, overflows, "splats", first_share);
    const int layer = film.layout.find("chains");
    const uint32_t words = film.layout.layers[size_t(layer)].words;
    const uint32_t* chains = film.layer(size_t(layer));
    auto word_float = [](uint32_t w) {
      float f;
      std::memcpy(&f, &w, sizeof f);
      return double(f);
    };
    double sum = 0, samples = 0;
    for (uint32_t c = 0; film.spp > 0 && c < film.layout.pixels; ++c) {
      const uint32_t* state = chains + size_t(c) * words;
      samples += state[9];
      sum += word_float(state[10]) - word_float(state[11]);
    }
    const double b0 = film.spp > 0 && lt.bootstrap > 0 ? word_float(chains[1]) / lt.bootstrap : 0;
    const uint32_t depths = ((words - kHeaderWords) / 5 - 4) / 4 - 1;  // D - 1
    const double b = b0 > 0 ? depths * (word_float(chains[1]) + sum) / (double(lt.bootstrap) * depths + samples) : 0;
    const double scale = b0 > 0 ? b / b0 : 1;
    for (size_t i = 0; i < film.mean.size(); ++i) {
      // a chain's large steps and Metropolis samples are of one estimate: their halves' differences add
      const double chains_even = large.even_mean[i] + film.even_mean[i] * scale;
      const double chains_odd = large.odd_mean[i] + film.odd_mean[i] * scale, d = chains_even - chains_odd;
      film.mean[i] = float(own.mean[i] + large.mean[i] + film.mean[i] * scale);
      film.even_mean[i] = float(own.even_mean[i] + chains_even);
      film.odd_mean[i] = float(own.odd_mean[i] + chains_odd);
      film.variance[i] = float(own.variance[i] + first_share * (1 - first_share) * d * d);
    }
  };
  return t;
}
