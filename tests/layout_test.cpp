// The shared structs have the same size and field offsets on the host and as the kernel compiler sees
// them on the test device.
#include <gtest/gtest.h>

#include "runtime/kernel_sources.h"
#include "test_support.h"  // and through it kernels/shared/types.h, light_types.h and film_types.h

TEST(Layout, SharedStructsMatchTheDevice) {
  ClContext& cl = test_device();
  KernelProgram program = build_kernel_program(cl, "tests.cl", kernel_options(kFeatureAll));
  std::vector<std::string> names;
  std::vector<uint32_t> host;
#define HOST_SIZE(S)         \
  names.push_back("sizeof " #S); \
  host.push_back(uint32_t(sizeof(S)));
#define HOST_OFFSET(S, F)           \
  names.push_back("offsetof " #S "." #F); \
  host.push_back(uint32_t(offsetof(S, F)));
  PC_LAYOUT_STRUCTS(HOST_SIZE)
  PC_LAYOUT_FIELDS(HOST_OFFSET)
  PC_LIGHT_LAYOUT_STRUCTS(HOST_SIZE)
  PC_LIGHT_LAYOUT_FIELDS(HOST_OFFSET)
  PC_FILM_LAYOUT_STRUCTS(HOST_SIZE)
  PC_FILM_LAYOUT_FIELDS(HOST_OFFSET)
  ClBuffer out(cl, CL_MEM_WRITE_ONLY, host.size() * sizeof(uint32_t));
  ClKernel kernel(program.kernel("layout_report"));
  kernel.arg(0, out.mem);
  run_kernel(cl, kernel.k, 1);
  std::vector<uint32_t> device(host.size());
  CL_CHECK(clEnqueueReadBuffer(cl.queue, out.mem, CL_TRUE, 0, device.size() * 4, device.data(), 0, nullptr, nullptr));
  for (size_t i = 0; i < host.size(); ++i) EXPECT_EQ(device[i], host[i]) << names[i];
  EXPECT_GT(host.size(), 40u);
}

TEST(Layout, KernelSourcesCarryLineMarkers) {
  std::string source = assemble_kernel_source("integrator.cl");
  EXPECT_NE(source.find("#line 1 \"intersect.cl\""), std::string::npos);
  EXPECT_NE(source.find("#line 1 \"shared/types.h\""), std::string::npos);
  // Each file is included once even though several files include math.cl.
  EXPECT_EQ(source.find("#line 1 \"math.cl\""), source.rfind("#line 1 \"math.cl\""));
  // A template is expanded at every include, its lines marked each time: the diffuse lobe at 1, 8 and 16
  // lanes, each an overload of its own.
  auto count = [&](const std::string& text) {
    size_t n = 0;
    for (size_t at = source.find(text); at != std::string::npos; at = source.find(text, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("#line 1 \"templates/bsdf_diffuse.cl\""), 3u);
  EXPECT_EQ(count("inline PC_OVL V3 diffuse_eval_lanes(V3 c, V3 wi)"), 3u);
  EXPECT_EQ(count("#define PC_DIFFUSE_LANES"), 0u);
}
