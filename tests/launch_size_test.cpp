// GPU launch sizing (runtime/renderer.cpp, adapt_launch_size): on a simulated device whose launch time
// is proportional to samples x pixels, the policy settles on launches of 50-100 ms from any speed, or
// at its limits (256 samples per pass over the whole film; 1 sample over 1024 pixels). No timing here:
// the device is a cost model, so the test is exact and fast.
#include <gtest/gtest.h>

#include "runtime/renderer.h"

namespace {

struct Settled {
  LaunchSize size;
  double launch_ms = 0;
  int passes = 0;
};

// Starts as the renderer does (1 sample per pass, the whole film per launch) and applies the policy
// until it stops changing the size.
Settled settle(double ms_per_sample, size_t pixels) {
  LaunchSize size{1, pixels};
  for (int pass = 1; pass <= 100; ++pass) {
    double slowest = ms_per_sample * size.pass_spp * double(std::min(size.launch_pixels, pixels));
    LaunchSize next = adapt_launch_size(size, slowest, pixels);
    if (next.pass_spp == size.pass_spp && next.launch_pixels == size.launch_pixels) return {size, slowest, pass};
    size = next;
  }
  ADD_FAILURE() << "the launch size never settled";
  return {};
}

}  // namespace

TEST(LaunchSize, SettlesInTheWindowFromAnySpeed) {
  const size_t pixels = 1 << 20;
  // From a device that needs 32 samples per pass to one that must split the film 16 ways.
  for (double ms_per_sample : {3e-6, 1e-5, 4e-5, 1e-4, 1e-3}) {
    Settled s = settle(ms_per_sample, pixels);
    EXPECT_GE(s.launch_ms, 50) << ms_per_sample << " ms per sample";
    EXPECT_LE(s.launch_ms, 100) << ms_per_sample << " ms per sample";
    EXPECT_LE(s.passes, 20);
    EXPECT_EQ(s.size.launch_pixels % 1024, 0u);
    // Pixels are split only when one sample over the whole film is already too slow.
    EXPECT_EQ(s.size.launch_pixels < pixels, ms_per_sample * pixels > 100) << ms_per_sample;
  }
}

TEST(LaunchSize, StopsAtItsLimits) {
  const size_t pixels = 1 << 20;
  Settled fast = settle(1e-9, pixels);  // even 256 samples over the whole film take 0.27 ms
  EXPECT_EQ(fast.size.pass_spp, 256u);
  EXPECT_EQ(fast.size.launch_pixels, pixels);
  Settled slow = settle(1.0, pixels);  // 1024 pixels at 1 sample take a second: nothing smaller is tried
  EXPECT_EQ(slow.size.pass_spp, 1u);
  EXPECT_EQ(slow.size.launch_pixels, 1024u);
  Settled small_film = settle(1e-3, 5000);  // 5 ms per sample over the film: more samples, one launch
  EXPECT_EQ(small_film.size.launch_pixels, 5000u);
  EXPECT_EQ(small_film.size.pass_spp, 16u);
  EXPECT_GE(small_film.launch_ms, 50);
  EXPECT_LE(small_film.launch_ms, 100);
}
