// Interrupt, checkpoint and resume: a stopped render writes what it has; a resumed render gives exactly
// the pixels of an uninterrupted one; damaged or foreign checkpoints are refused.
#include <algorithm>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <thread>

#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "runtime/image_io.h"
#include "test_support.h"

namespace fs = std::filesystem;

namespace {

const std::string kScene = std::string(PATHCL_TEST_SCENES) + "/tiny.json";
const std::string kSettings = " --spp 1500 --pass-spp 3 --seed 7 --max-depth 4 --quiet";

// Starts pathcl in the background; returns its pid.
pid_t start_pathcl(const std::string& args) {
  pid_t pid = fork();
  if (pid == 0) {
    std::string command = std::string("exec ") + PATHCL_BINARY + " " + args + " 2>/dev/null";
    execl("/bin/sh", "sh", "-c", command.c_str(), (char*)nullptr);
    _exit(127);
  }
  return pid;
}

// Up to two minutes: the first render of a kernel builds it (seconds on a loaded machine with cold caches).
bool wait_for_file(const std::string& path) {
  for (int i = 0; i < 24000 && !fs::exists(path); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  return fs::exists(path);
}

std::vector<float> pixels_of(const std::string& exr) { return read_exr(exr).rgb; }

}  // namespace

TEST(Interrupt, SigintWritesTheImageSoFarAndResumeIsBitIdentical) {
  std::string dir = temp_dir() + "/sigint", ck = dir + "/state.ck";
  fs::create_directories(dir);
  pid_t pid = start_pathcl("render " + kScene + kSettings + " -o " + dir + "/part.exr --checkpoint " + ck +
                           " --checkpoint-every 0");
  ASSERT_TRUE(wait_for_file(ck));
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  Image part = read_exr(dir + "/part.exr");
  EXPECT_EQ(part.attributes["stop_reason"], "interrupted");
  EXPECT_LT(part.spp, 1500);
  EXPECT_GT(part.spp, 0);

  std::string err;
  ASSERT_EQ(run_pathcl("render " + kScene + kSettings + " -o " + dir + "/resumed.exr --resume " + ck, &err), 0) << err;
  ASSERT_EQ(run_pathcl("render " + kScene + kSettings + " -o " + dir + "/whole.exr", &err), 0) << err;
  EXPECT_EQ(read_exr(dir + "/resumed.exr").spp, 1500);
  EXPECT_EQ(pixels_of(dir + "/resumed.exr"), pixels_of(dir + "/whole.exr"));
}

// The light integrator's checkpoint holds its integer splat film: interrupted, resumed, it gives the bits
// of an uninterrupted render; a checkpoint of one integrator is refused by the other.
TEST(Interrupt, LightIntegratorSigintAndResumeIsBitIdentical) {
  std::string dir = temp_dir() + "/sigint-light", ck = dir + "/state.ck", path_ck = dir + "/path.ck";
  fs::create_directories(dir);
  const std::string light = kSettings + " --integrator light";
  pid_t pid = start_pathcl("render " + kScene + light + " -o " + dir + "/part.exr --checkpoint " + ck +
                           " --checkpoint-every 0");
  ASSERT_TRUE(wait_for_file(ck));
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  Image part = read_exr(dir + "/part.exr");
  EXPECT_EQ(part.attributes["stop_reason"], "interrupted");
  EXPECT_EQ(part.attributes["integrator"], "light");
  EXPECT_LT(part.spp, 1500);
  EXPECT_GT(part.spp, 0);

  std::string err;
  ASSERT_EQ(run_pathcl("render " + kScene + light + " -o " + dir + "/resumed.exr --resume " + ck, &err), 0) << err;
  ASSERT_EQ(run_pathcl("render " + kScene + light + " -o " + dir + "/whole.exr", &err), 0) << err;
  Image resumed = read_exr(dir + "/resumed.exr"), whole = read_exr(dir + "/whole.exr");
  EXPECT_EQ(resumed.spp, 1500);
  EXPECT_EQ(resumed.rgb, whole.rgb);
  EXPECT_GT(*std::max_element(whole.rgb.begin(), whole.rgb.end()), 0.0f);

  // A light checkpoint does not resume a path render, nor a path checkpoint a light render.
  EXPECT_EQ(run_pathcl("render " + kScene + kSettings + " -o " + dir + "/x.exr --resume " + ck, &err), 2);
  EXPECT_NE(err.find("the checkpoint is of the light integrator, this render uses path"), std::string::npos) << err;
  ASSERT_EQ(run_pathcl("render " + kScene + " --spp 2 --seed 7 --max-depth 4 --quiet -o " + dir + "/p.exr --checkpoint " +
                           path_ck, &err), 0) << err;
  EXPECT_EQ(run_pathcl("render " + kScene + " --spp 2 --seed 7 --max-depth 4 --quiet --integrator light -o " + dir +
                           "/x.exr --resume " + path_ck, &err), 2);
  EXPECT_NE(err.find("the checkpoint is of the path integrator, this render uses light"), std::string::npos) << err;
}

TEST(Interrupt, KillNineLosesAtMostOneIntervalAndResumes) {
  std::string dir = temp_dir() + "/kill", ck = dir + "/state.ck";
  fs::create_directories(dir);
  pid_t pid = start_pathcl("render " + kScene + kSettings + " -o " + dir + "/never.exr --checkpoint " + ck +
                           " --checkpoint-every 0");
  ASSERT_TRUE(wait_for_file(ck));
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  std::string err;
  ASSERT_EQ(run_pathcl("render " + kScene + kSettings + " -o " + dir + "/resumed.exr --resume " + ck, &err), 0) << err;
  ASSERT_EQ(run_pathcl("render " + kScene + kSettings + " -o " + dir + "/whole.exr", &err), 0) << err;
  EXPECT_EQ(pixels_of(dir + "/resumed.exr"), pixels_of(dir + "/whole.exr"));
}

// No file of the render's directory is a temporary file left half-written.
bool no_partial_files(const std::string& dir) {
  for (const auto& entry : fs::directory_iterator(dir))
    if (entry.path().filename().string().find(".partial") != std::string::npos) return false;
  return true;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// GNU timeout, shells and process managers send a signal to the process and then to its group; an
// impatient user presses Ctrl-C twice. The image so far must still be written, every time.
TEST(Interrupt, TwoSignalsBackToBackStillWriteTheImage) {
  for (int round = 0; round < 4; ++round) {
    std::string dir = temp_dir() + "/twice" + std::to_string(round), ck = dir + "/state.ck";
    fs::create_directories(dir);
    pid_t pid = start_pathcl("render " + kScene + kSettings + " -o " + dir + "/out.exr --checkpoint " + ck +
                             " --checkpoint-every 0");
    ASSERT_TRUE(wait_for_file(ck));
    if (round % 2) std::this_thread::sleep_for(std::chrono::milliseconds(50 * round));
    kill(pid, SIGINT);
    if (round == 3) std::this_thread::sleep_for(std::chrono::milliseconds(200));
    kill(pid, round == 2 ? SIGTERM : SIGINT);
    int status = 0;
    waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFEXITED(status)) << "round " << round;
    // 128 + the signal handled first; SIGINT and SIGTERM sent together may be handled in either order.
    EXPECT_TRUE(WEXITSTATUS(status) == 130 || (round == 2 && WEXITSTATUS(status) == 143))
        << "round " << round << ": exit " << WEXITSTATUS(status);
    Image out = read_exr(dir + "/out.exr");
    EXPECT_EQ(out.attributes["stop_reason"], "interrupted");
    EXPECT_GT(out.spp, 0);
    EXPECT_TRUE(no_partial_files(dir));
  }
}

TEST(Interrupt, TimeoutsSignalToTheProcessAndItsGroupStillWritesTheImage) {
  std::string dir = temp_dir() + "/timeout";
  fs::create_directories(dir);
  for (int round = 0; round < 3; ++round) {
    std::string out = dir + "/out" + std::to_string(round) + ".exr";
    int status = std::system(("timeout --preserve-status -s INT 1 " + std::string(PATHCL_BINARY) + " render " + kScene +
                              " --spp 100000 --pass-spp 3 --quiet -o " + out + " 2>/dev/null").c_str());
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 130) << "round " << round;
    EXPECT_GT(read_exr(out).spp, 0) << "round " << round;
  }
  EXPECT_TRUE(no_partial_files(dir));
}

// A third signal ends the process at once: no image, no temporary file, a message saying what is lost;
// the checkpoint is intact.
// The signals are 30 ms apart: a signal that arrives while the same one is pending is merged with it.
// The film is large (1024 x 512, 1 spp a pass), so that finishing the pass and writing the checkpoint
// and the image take far longer than the 60 ms the signals need.
TEST(Interrupt, ThirdSignalEndsAtOnceAndSaysWhatIsLost) {
  std::string dir = temp_dir() + "/thrice", ck = dir + "/state.ck", err = dir + "/stderr.txt";
  fs::create_directories(dir);
  std::string scene = read_text(kScene);
  const std::string small_film = "\"width\": 24, \"height\": 16";
  scene.replace(scene.find(small_film), small_film.size(), "\"width\": 1024, \"height\": 512");
  scene.replace(scene.find("../.."), 5, std::string(PATHCL_TEST_SCENES) + "/../..");
  std::string big = write_temp_file("big.json", scene);
  pid_t pid = fork();
  if (pid == 0) {
    std::string command = std::string("exec ") + PATHCL_BINARY + " render " + big +
                          " --spp 1000 --pass-spp 1 --max-depth 4 --quiet -o " + dir + "/out.exr --checkpoint " + ck +
                          " --checkpoint-every 0 2>" + err;
    execl("/bin/sh", "sh", "-c", command.c_str(), (char*)nullptr);
    _exit(127);
  }
  ASSERT_TRUE(wait_for_file(ck)) << read_text(err);
  for (int i = 0; i < 3; ++i) {
    kill(pid, SIGINT);
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
  }
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  std::string message = read_text(err);
  EXPECT_NE(message.find("interrupted again, exiting at once: " + dir + "/out.exr is not written; the checkpoint " + ck +
                         " holds the render"),
            std::string::npos)
      << message;
  EXPECT_FALSE(fs::exists(dir + "/out.exr"));
  EXPECT_TRUE(no_partial_files(dir));
  std::string e;
  EXPECT_EQ(run_pathcl("render " + big + " --spp 1000 --time 0.2 --pass-spp 1 --max-depth 4 --quiet -o " + dir +
                           "/resumed.exr --resume " + ck, &e),
            0)
      << e;
}

TEST(Interrupt, DamagedOrForeignCheckpointsAreRefused) {
  std::string dir = temp_dir() + "/refuse", ck = dir + "/state.ck";
  fs::create_directories(dir);
  std::string err;
  ASSERT_EQ(run_pathcl("render " + kScene + " --spp 4 --quiet -o " + dir + "/a.exr --checkpoint " + ck, &err), 0) << err;
  EXPECT_EQ(run_pathcl("render " + kScene + " --spp 4 --seed 99 --quiet -o " + dir + "/b.exr --resume " + ck, &err), 2);
  EXPECT_NE(err.find("another scene or other settings"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir + "/b.exr"));
  {
    std::fstream f(ck, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(100);
    f.put('\x5a');
  }
  EXPECT_EQ(run_pathcl("render " + kScene + " --spp 4 --quiet -o " + dir + "/c.exr --resume " + ck, &err), 2);
  EXPECT_NE(err.find("damaged"), std::string::npos) << err;
  std::ofstream(dir + "/junk.ck") << "not a checkpoint";
  EXPECT_EQ(run_pathcl("render " + kScene + " --spp 4 --quiet -o " + dir + "/d.exr --resume " + dir + "/junk.ck", &err), 2);
  EXPECT_NE(err.find("not a pathcl checkpoint"), std::string::npos) << err;
}
