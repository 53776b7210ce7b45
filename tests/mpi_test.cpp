// Renders over the ranks of an MPI job (runtime/ranks.h), run with Open MPI's mpiexec on this machine
// (shared memory, several processes per core): the image is the bits of a one-process render for any number
// of ranks, device sets and timings, for path and for the splatting integrators bdpt and vcm; a killed rank
// ends the job and the checkpoint resumes with another number of ranks; with --enable-recovery a lost rank's
// units are rendered by the others; a rank that sends garbage is dropped; a rank of another arithmetic class is
// left out unless mixed devices are allowed.
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>

#include <sys/wait.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "runtime/image_io.h"
#include "test_support.h"

namespace {

const std::string kScene = std::string(PATHCL_TEST_SCENES) + "/tiny.json";
const std::string kPathcl = PATHCL_BINARY;

// Open MPI as root in a container, over shared memory only (no network).
class MpiEnvironment : public ::testing::Environment {
 public:
  void SetUp() override {
    setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
    setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
    setenv("OMPI_MCA_btl", "self,vader", 1);
    setenv("OMPI_MCA_btl_vader_single_copy_mechanism", "none", 1);
  }
};
const auto* const kEnvironment = ::testing::AddGlobalTestEnvironment(new MpiEnvironment);

// Each job within 3 minutes (they take seconds): a job that hangs fails its test instead of holding CI.
std::string mpiexec(const std::string& options = "") {
  return "timeout -k 10 180 " + std::string(PATHCL_MPIEXEC) + " --oversubscribe " + options + " ";
}

// Runs a shell command; its exit code (-1 if it did not exit), stderr in *err.
int run(const std::string& command, std::string* err) {
  std::string err_file = temp_dir() + "/mpi-stderr.txt";
  int status = std::system((command + " >/dev/null 2>" + err_file).c_str());
  *err = read_text_file(err_file);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string out(const std::string& name) { return temp_dir() + "/mpi-" + name; }

// The render's settings, the same in every process of a job and in the reference.
std::string settings(const std::string& integrator) { return " --spp 12 --seed 3 --variance --integrator " + integrator; }

bool same_bits(const Image& a, const Image& b) {
  return a.rgb.size() == b.rgb.size() && a.variance.size() == b.variance.size() && a.spp == b.spp &&
         std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)) == 0 &&
         std::memcmp(a.variance.data(), b.variance.data(), a.variance.size() * sizeof(float)) == 0;
}

// The one-process image (no mpiexec) every job below must match.
const Image& reference(const std::string& integrator) {
  static std::map<std::string, Image> images;
  auto it = images.find(integrator);
  if (it != images.end()) return it->second;
  std::string err, file = out("reference-" + integrator + ".exr");
  EXPECT_EQ(run(kPathcl + " render " + kScene + settings(integrator) + " -o " + file, &err), 0) << err;
  return images[integrator] = read_exr(file);
}

nlohmann::json read_stats(const std::string& path) { return nlohmann::json::parse(read_text_file(path)); }

}  // namespace

TEST(MpiRender, AnyNumberOfRanksGivesTheOneProcessBits) {
  // path (ordered units), bdpt (ordered and commutative layers) and vcm (per-sample units: one iteration's
  // light paths and camera paths in one unit) on 1, 2 and 3 ranks; light, bpm, sppm, instant radiosity and
  // radiosity (per-sample pixel units) on 3.
  for (const std::string integrator : {"path", "bdpt", "vcm", "light", "bpm", "sppm", "instant_radiosity", "radiosity", "mlt"}) {
    const bool all_counts = integrator == "path" || integrator == "bdpt" || integrator == "vcm";
    // The one-process render first: it builds the kernels and PoCL's work-group functions once, which the
    // ranks then load from the caches (on empty caches the kernel cache's lock has one rank build each
    // program, but every rank would compile PoCL's work-group functions at its first launches).
    reference(integrator);
    for (int ranks : {1, 2, 3}) {
      if (!all_counts && ranks != 3) continue;
      SCOPED_TRACE(integrator + " on " + std::to_string(ranks) + " ranks");
      std::string file = out("ranks.exr"), stats = out("ranks.json"), err;
      // Two ranks: rank 0 only coordinates, so that every unit crosses between processes.
      std::string coordinator = ranks == 2 ? " --coordinator-only" : "";
      ASSERT_EQ(run(mpiexec("-n " + std::to_string(ranks)) + kPathcl + " render " + kScene + settings(integrator) +
                        coordinator + " -o " + file + " --stats " + stats,
                    &err),
                0)
          << err;
      EXPECT_TRUE(same_bits(read_exr(file), reference(integrator)));
      nlohmann::json j = read_stats(stats);
      if (ranks == 1) {
        EXPECT_FALSE(j.contains("ranks"));  // one rank is one process, as without mpiexec
        continue;
      }
      ASSERT_EQ(j["ranks"].size(), size_t(ranks));
      EXPECT_EQ(j["lost_ranks"], 0);
      if (ranks == 2) {
        EXPECT_EQ(j["ranks"][0]["units"], 0);
        EXPECT_EQ(j["ranks"][1]["samples"], 24 * 16 * 12);
        EXPECT_GT(j["ranks"][1]["transfer_bytes"].get<uint64_t>(), 0u);
      }
    }
  }
}

TEST(MpiRender, RanksWithOtherDeviceSetsAndASlowRankGiveTheSameBits) {
  // MPMD: rank 0 coordinates; rank 1 has two PoCL devices (each a unit worker of its own), rank 2 one,
  // lagging 50 ms a unit. Every device finishes units (committed, or compared with a faster copy).
  std::string file = out("mpmd.exr"), stats = out("mpmd.json"), err;
  ASSERT_EQ(run(mpiexec() + "-n 1 " + kPathcl + " render " + kScene + settings("path") + " --coordinator-only -o " +
                    file + " --stats " + stats + " : -n 1 -x 'POCL_DEVICES=pthread pthread' " + kPathcl + " render " +
                    kScene + " --device all : -n 1 -x POCL_DEVICES=pthread " + kPathcl + " render " + kScene +
                    " --debug-rank-delay 0.05",
                &err),
            0)
      << err;
  EXPECT_TRUE(same_bits(read_exr(file), reference("path")));
  nlohmann::json j = read_stats(stats);
  ASSERT_EQ(j["ranks"].size(), 3u);
  EXPECT_EQ(j["ranks"][1]["devices"].size(), 2u);
  ASSERT_EQ(j["devices"].size(), 3u);
  for (const auto& d : j["devices"]) EXPECT_GT(d["busy_seconds"].get<double>(), 0) << d.dump();
}

TEST(MpiRender, AKilledRankEndsTheJobAndItsCheckpointResumesWithOtherRanks) {
  // Open MPI's default: a process that dies ends the job. The checkpoint (rank 0's, at every pass) holds the
  // render as of its last pass; resumed with three ranks, or in one process, it gives the same bits. Rank 1
  // renders every unit (rank 0 only coordinates) and dies when asked for its third.
  std::string file = out("killed.exr"), checkpoint = out("killed.ckpt"), err;
  std::filesystem::remove(file);
  std::filesystem::remove(checkpoint);
  EXPECT_NE(run(mpiexec() + "-n 1 " + kPathcl + " render " + kScene + settings("bdpt") + " --coordinator-only --pass-spp 1 -o " + file +
                    " --checkpoint " + checkpoint + " --checkpoint-every 0 : -n 1 " + kPathcl + " render " + kScene +
                    " --debug-rank-kill-after 2",
                &err),
            0);
  EXPECT_NE(err.find("signal 9"), std::string::npos) << err;
  ASSERT_TRUE(std::filesystem::exists(checkpoint)) << err;
  // Its spp (runtime/checkpoint.cpp's header: magic, key, width, height, spp): some of the render, not all.
  std::string head = read_text_file(checkpoint).substr(0, 28);
  uint32_t checkpoint_spp = 0;
  std::memcpy(&checkpoint_spp, head.data() + 24, 4);
  EXPECT_GT(checkpoint_spp, 0u);
  EXPECT_LT(checkpoint_spp, 12u);
  for (std::string launcher : {mpiexec("-n 3"), std::string()}) {
    std::string resumed = out("resumed.exr");
    ASSERT_EQ(run(launcher + kPathcl + " render " + kScene + settings("bdpt") + " --resume " + checkpoint + " -o " + resumed, &err), 0)
        << err;
    EXPECT_TRUE(same_bits(read_exr(resumed), reference("bdpt"))) << launcher;
  }
}

TEST(MpiRender, WithRecoveryALostRanksUnitsAreRenderedByTheOthers) {
  // mpirun --enable-recovery keeps the job going when a process dies (and then exits 0 itself): rank 0
  // gives the rank up after --rank-timeout, finishes the image and exits 1, which a wrapper keeps here. Rank 1
  // dies when asked for its first unit (every device gets one at the start; a later one may never come in a
  // render this small).
  std::string file = out("recovered.exr"), stats = out("recovered.json"), code = out("recovered.code"), err;
  std::filesystem::remove(code);
  run(mpiexec("--enable-recovery") + "-n 1 sh -c '" + kPathcl + " render " + kScene + settings("path") +
          " --pass-spp 1 --rank-timeout 1 -o " + file + " --stats " + stats + "; echo $? >" + code + "' : -n 1 " +
          kPathcl + " render " + kScene + " --debug-rank-kill-after 0 : -n 1 " + kPathcl + " render " + kScene,
      &err);
  EXPECT_EQ(read_text_file(code), "1\n") << err;
  EXPECT_TRUE(same_bits(read_exr(file), reference("path")));
  nlohmann::json j = read_stats(stats);
  EXPECT_EQ(j["lost_ranks"], 1);
  EXPECT_EQ(j["ranks"][1]["lost"], true);
  EXPECT_EQ(j["ranks"][2]["lost"], false);
  EXPECT_NE(err.find("lost rank 1"), std::string::npos) << err;
}

TEST(MpiRender, ARankThatSendsGarbageIsDropped) {
  std::string file = out("garbage.exr"), stats = out("garbage.json"), err;
  EXPECT_EQ(run(mpiexec() + "-n 1 " + kPathcl + " render " + kScene + settings("bdpt") + " -o " + file + " --stats " +
                    stats + " : -n 1 " + kPathcl + " render " + kScene + " --debug-rank-corrupt",
                &err),
            1)
      << err;
  EXPECT_TRUE(same_bits(read_exr(file), reference("bdpt")));
  EXPECT_EQ(read_stats(stats)["lost_ranks"], 1);
  EXPECT_NE(err.find("sent garbage"), std::string::npos) << err;
}

TEST(MpiRender, ARankOfAnotherArithmeticClassIsLeftOutUnlessMixedIsAllowed) {
  // Rank 1's devices compute other bits (PC_DEBUG_PERTURB): its probe differs from rank 0's device's, so it
  // is left out and the image keeps the one-process bits; with --allow-mixed-devices it renders, and the
  // image says determinism "mixed".
  for (bool mixed : {false, true}) {
    SCOPED_TRACE(mixed ? "mixed allowed" : "left out");
    std::string file = out("class.exr"), stats = out("class.json"), err;
    ASSERT_EQ(run(mpiexec() + "-n 1 " + kPathcl + " render " + kScene + settings("path") + " -o " + file + " --stats " +
                      stats + (mixed ? " --allow-mixed-devices" : "") + " : -n 1 " + kPathcl + " render " + kScene +
                      " --debug-rank-perturb",
                  &err),
              0)
        << err;
    nlohmann::json j = read_stats(stats);
    ASSERT_EQ(j["devices"].size(), 2u);
    EXPECT_EQ(j["devices"][1]["rank"], 1);
    EXPECT_EQ(j["devices"][1]["class"], 1);
    EXPECT_EQ(j["lost_ranks"], 0);
    if (!mixed) {
      EXPECT_TRUE(same_bits(read_exr(file), reference("path")));
      EXPECT_EQ(j["devices"][1]["used"], false);
      EXPECT_EQ(j["determinism"], "bitwise");
      EXPECT_NE(err.find("another arithmetic class"), std::string::npos) << err;
    } else {
      EXPECT_EQ(j["devices"][1]["used"], true);
      EXPECT_EQ(j["determinism"], "mixed");
    }
  }
}

TEST(MpiRender, RankZeroShowsTheProgressBarOnMpirunsTerminal) {
  // script(1) gives mpiexec a terminal; Open MPI passes rank 0 a terminal for stdout and a pipe for stderr.
  std::string file = out("progress.exr"), log = out("progress.txt"), err;
  ASSERT_EQ(run("script -qec \"" + mpiexec("-n 2") + kPathcl + " render " + kScene + settings("path") + " -o " + file +
                    "\" " + log,
                &err),
            0)
      << err;
  const std::string text = read_text_file(log);
  EXPECT_NE(text.find("12/12 spp"), std::string::npos) << text;
  EXPECT_NE(text.find("Msamples/s  ETA"), std::string::npos) << text;
}

TEST(MpiRender, BadRankOptionsAreUsageErrors) {
  std::string err;
  EXPECT_EQ(run(kPathcl + " render " + kScene + " --rank-timeout 0 -o " + out("x.exr"), &err), 2);
  EXPECT_NE(err.find("--rank-timeout"), std::string::npos) << err;
  EXPECT_EQ(run(kPathcl + " render " + kScene + " --coordinator-only -o " + out("x.exr"), &err), 2);
  EXPECT_NE(err.find("no other rank"), std::string::npos) << err;
}
