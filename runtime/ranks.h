// A render over the ranks of an MPI job (`mpirun -np K pathcl render ...`, Open MPI). Rank 0 loads the
// scene, builds the device scene once and runs the render loop (runtime/renderer.h); each device of every
// other rank is one more unit worker of that loop (a RemoteWorker, runtime/ranks.cpp), scheduled, probed and
// checked like a local device. Rank 0 sends the device scene once to each rank (its bytes and their
// checksum: ranks need no shared file system, and no rank loads, cleans or builds a BVH again), then each
// worker's settings, and the work units with the accumulators of their pixels; a rank sends back the
// units' results. The other ranks print nothing unless they fail; rank 0 owns the film, all output, the
// progress bar and the checkpoints. The image is the same bits as a one-process render for any number of
// ranks (runtime/render_schedule.h).
//
// A rank that stops answering (no answer within its deadline: --rank-timeout seconds plus four times the
// unit's expected time) or that sends a malformed answer is lost: its devices leave the render, their units
// go to the others, and rank 0 reports it. Under Open MPI's default a dead process ends the whole job (then
// --checkpoint and --resume continue the render, with any number of ranks); with `mpirun --enable-recovery`
// the job goes on without it.
//
// Built with MPI when CMake finds it (PATHCL_MPI); without mpirun, or without MPI, pathcl is one process.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "runtime/renderer.h"

// This machine's host name (gethostname).
std::string host_name();

// This process's part of an MPI job: MPI is initialised when the process was launched by mpirun or
// mpiexec (Open MPI's, PMIx's or Hydra's environment) and finalised when the job object goes away. A
// process not launched so is the job's only rank.
class RankJob {
 public:
  // UsageError when launched by mpirun with more than one rank but built without MPI.
  RankJob(int* argc, char*** argv);
  ~RankJob();
  RankJob(const RankJob&) = delete;
  RankJob& operator=(const RankJob&) = delete;
  int rank() const { return rank_; }
  int size() const { return size_; }

  // Rank 0: the devices of ranks 1 .. K-1 as unit workers (each rank's list, in rank order). A rank whose
  // devices could not be chosen is left out with a warning. timeout_seconds: --rank-timeout.
  std::vector<WorkerSource> remote_workers(double timeout_seconds, std::vector<std::string>* warnings);
  // Rank 0: the ranks lost during the render, in rank order.
  struct LostRank {
    int rank = 0;
    std::string why;  // "rank 2 (host): no answer ..."
  };
  std::vector<LostRank> lost_ranks() const;
  // Rank 0: ends the job's other ranks (also done when the job goes away).
  void finish();

  // Test-only faults of a rank other than 0: a delay before each unit, the process killed (SIGKILL) when
  // asked for a unit after this many, damaged answers, arithmetic that differs in one operation.
  struct Faults {
    double unit_delay = 0;
    int64_t kill_after_units = -1;
    bool corrupt_answers = false;  // a byte of every unit's answer flipped: a rank that sends garbage
    bool perturb = false;          // its devices built with PC_DEBUG_PERTURB: another arithmetic class
  };
  // Ranks other than 0: sends rank 0 this rank's devices (those `selector` picks, as --device) and runs the
  // units rank 0 sends until it says the render is over. Returns the exit code (1 after a failure, which it
  // prints).
  int serve(const std::string& selector, const Faults& faults);

  struct Impl;

 private:
  int rank_ = 0, size_ = 1;
  std::unique_ptr<Impl> impl_;
};
