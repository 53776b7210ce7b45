// Interrupt, checkpoint and resume: a stopped render writes what it has; a resumed render gives exactly
// the pixels of an uninterrupted one; damaged or foreign checkpoints are refused.
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
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

bool wait_for_file(const std::string& path) {
  for (int i = 0; i < 2000 && !fs::exists(path); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
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

TEST(Interrupt, SecondSignalEndsAtOnceWithoutAHalfWrittenImage) {
  std::string dir = temp_dir() + "/twice", ck = dir + "/state.ck";
  fs::create_directories(dir);
  pid_t pid = start_pathcl("render " + kScene + kSettings + " -o " + dir + "/out.exr --checkpoint " + ck +
                           " --checkpoint-every 0");
  ASSERT_TRUE(wait_for_file(ck));
  kill(pid, SIGINT);
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  // Either the first signal's clean exit won the race, or the second one ended the process.
  EXPECT_TRUE((WIFEXITED(status) && WEXITSTATUS(status) == 130) || (WIFSIGNALED(status) && WTERMSIG(status) == SIGINT));
  if (fs::exists(dir + "/out.exr")) EXPECT_NO_THROW(read_exr(dir + "/out.exr"));
  std::string err;
  EXPECT_EQ(run_pathcl("render " + kScene + kSettings + " -o " + dir + "/resumed.exr --resume " + ck, &err), 0) << err;
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
