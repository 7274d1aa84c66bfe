// `mpirun -np 2 weft train` on the tiny dataset, one thread per rank, against one process
// that runs the same two shards of every batch in turn (config key `shards: 2`):
// - after every step the parameters and batch-norm statistics are the same (the
//   checksums of RUN/parameters.csv are equal: the two shards' float32 gradients are
//   summed as a + b on one process and by the all-reduce on two, which is the same
//   number, so the runs agree bit for bit; per-shard batch norm is why the reference
//   runs two shards, not one batch: a batch of 4 normalised as one is another model);
// - SIGKILL of rank 1 ends rank 0 and mpirun within a bounded time, with a message naming
//   rank 1;
// - `mpirun -np 2 weft train --resume` then continues exactly: the whole losses.csv and
//   parameters.csv equal the uninterrupted reference's;
// - SIGSTOP of rank 1 (a hang) ends the job once rank 0 has waited WEFT_MPI_TIMEOUT_S.
// Skipped, with the reason, when weft was built without MPI or mpirun is not on PATH.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fcntl.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "capture/studio/synthetic_studio.h"
#include "capture/training/loss_log.h"
#include "capture/training/trainer.h"
#include "graph/threads.h"
#include "nn/process_group.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
namespace fs = std::filesystem;

using weft::capture::testing::repo_file;

namespace {

fs::path scratch() { return fs::temp_directory_path() / ("weft_data_parallel_test_" + std::to_string(::getpid())); }

// mpirun on PATH, or empty.
std::string find_mpirun() {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  std::string dir;
  while (std::getline(dirs, dir, ':'))
    if (!dir.empty() && ::access((fs::path(dir) / "mpirun").c_str(), X_OK) == 0) return (fs::path(dir) / "mpirun").string();
  return {};
}

// The tiny config cut to 6 steps across the three stages (a checkpoint at the end of each), two
// shards per batch, the simulator's iterations cut so the physics steps stay short.
std::string write_config(const fs::path& dir) {
  const std::string path = (dir / "tiny_two_shards.yaml").string();
  std::ofstream out(path);
  out << "seed: 3\n"
         "network: {backbone: resnet18, input_size: 64}\n"
         "stages:\n"
         "  pose:    {steps: 2, batch_size: 4, lr: 2.0e-3, final_lr_fraction: 1, landmarks: 1}\n"
         "  warmup:  {steps: 2, batch_size: 4, lr: 1.0e-3, final_lr_fraction: 1, landmarks: 1, silhouette: 1, "
         "arap: 10, attachment: 10}\n"
         "  physics: {steps: 2, batch_size: 6, lr: 5.0e-4, final_lr_fraction: 1, landmarks: 1, silhouette: 1, "
         "simulation: 1, attachment: 10, arap: 10}\n"
         "physics: {window_frames: 3, max_iterations: 15, tolerance: 1.0e-2}\n"
         "silhouette_size: 64\nloader_threads: 0\nlog_every: 1\nvalidate_every: 0\nvalidation_samples: 2\n"
         "checkpoint_every: 100\nkeep_checkpoints: 2\nshards: 2\n";
  return path;
}

struct Mpirun {
  pid_t pid = -1;
  fs::path output;  // mpirun's and the ranks' stdout and stderr
};

// `mpirun -np 2 weft train --threads 1 ...` in the background.
Mpirun start_mpirun(const std::string& mpirun, const std::string& config, const fs::path& data, const fs::path& run,
                    bool resume, const char* timeout_s = nullptr) {
  Mpirun m;
  m.output = run.string() + (resume ? ".resume.out" : ".out");
  const std::string bin = std::string(WEFT_BINARY_DIR) + "/apps/weft";
  m.pid = ::fork();
  if (m.pid == 0) {
    const int out = ::open(m.output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(out, 1), ::dup2(out, 2);
    // Containers run tests as root; a machine with one core still gets two ranks.
    ::setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
    ::setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
    if (timeout_s) ::setenv("WEFT_MPI_TIMEOUT_S", timeout_s, 1);
    std::vector<std::string> args = {mpirun, "-np", "2", "--oversubscribe", "-x", "WEFT_MPI_TIMEOUT_S", bin, "train",
                                     "--threads", "1", "--config", config, "--data", data.string(), "--out",
                                     run.string(), "--parameter-checksums"};
    if (resume) args.push_back("--resume");
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(mpirun.c_str(), argv.data());
    ::_exit(127);
  }
  return m;
}

// Waits up to `seconds` for the process; its exit status, or −1 when it is still running.
int wait_for(pid_t pid, double seconds) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < deadline) {
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid) return status;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return -1;
}

// The pid of the process of rank `rank` among mpirun's children (OpenMPI sets
// OMPI_COMM_WORLD_RANK in each rank's environment), or −1.
pid_t rank_pid(pid_t mpirun, int rank) {
  for (const auto& e : fs::directory_iterator("/proc")) {
    const std::string name = e.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream stat(e.path() / "stat");
    std::string line;
    if (!std::getline(stat, line)) continue;
    const size_t close = line.rfind(')');
    if (close == std::string::npos) continue;
    std::istringstream rest(line.substr(close + 2));
    char state = 0;
    pid_t parent = 0;
    rest >> state >> parent;
    if (parent != mpirun) continue;
    const std::string env = slurp(e.path() / "environ");
    if (env.find(std::string("OMPI_COMM_WORLD_RANK=") + std::to_string(rank) + '\0') != std::string::npos)
      return pid_t(std::stoi(name));
  }
  return -1;
}

int64_t last_logged_step(const fs::path& run) {
  try {
    const auto rows = read_loss_log((run / "losses.csv").string());
    return rows.empty() ? 0 : rows.back().step;
  } catch (const weft::Error&) {  // between a rewrite's rename and its row
    return 0;
  }
}

}  // namespace

TEST(DataParallel, TwoRanksMatchTwoShardsOnOneProcessAndSurviveTheDeathOrHangOfARank) {
  REQUIRE_HUMAN();
  if (!weft::nn::ProcessGroup::built_with_mpi())
    GTEST_FAIL() << "weft was built without MPI (WEFT_WITH_MPI off: libopenmpi-dev was missing at configure time); "
                    "install it with scripts/setup.sh (or apt-get install libopenmpi-dev) and configure again";
  const std::string mpirun = find_mpirun();
  if (mpirun.empty())
    GTEST_FAIL() << "mpirun is not on PATH: install it with scripts/setup.sh (or apt-get install openmpi-bin)";
  const fs::path root = scratch();
  fs::remove_all(root);
  fs::create_directories(root);
  struct Cleanup {
    fs::path dir;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  } cleanup{root};
  const fs::path data = root / "tiny";
  synthesize_dataset(load_synth_config(repo_file("configs/synth/tiny.yaml")), data.string());
  const std::string config = write_config(root);

  // The reference: one process, one thread, the two shards of every batch in turn.
  const int threads = weft::num_threads();
  weft::set_num_threads(1);
  TrainOptions o;
  o.config = config;
  o.data = data.string();
  o.run = (root / "one_process").string();
  o.parameter_checksums = true;
  const TrainSummary reference = train(o);
  weft::set_num_threads(threads);
  ASSERT_EQ(reference.last_step, 6);

  // Two ranks, rank 1 killed once step 3 (the warm start's first) is logged.
  const fs::path run = root / "two_ranks";
  Mpirun first = start_mpirun(mpirun, config, data, run, false);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (last_logged_step(run) < 3 && std::chrono::steady_clock::now() < deadline && wait_for(first.pid, 0.02) == -1) {
  }
  const int64_t killed_after = last_logged_step(run);
  ASSERT_GE(killed_after, 3) << "the two-rank run ended or stalled before step 3:\n" << slurp(first.output);
  ASSERT_LT(killed_after, 6) << "the two-rank run finished before the kill";
  const pid_t victim = rank_pid(first.pid, 1);
  ASSERT_GT(victim, 0) << "no child of mpirun with OMPI_COMM_WORLD_RANK=1";
  ::kill(victim, SIGKILL);
  const auto killed_at = std::chrono::steady_clock::now();
  const int status = wait_for(first.pid, 30);
  if (status == -1) ::kill(first.pid, SIGKILL), ::waitpid(first.pid, nullptr, 0);
  ASSERT_NE(status, -1) << "rank 1 was killed and mpirun was still running 30 s later";
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - killed_at).count();
  EXPECT_FALSE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "the job ended as if nothing had happened";
  const std::string message = slurp(first.output);
  EXPECT_NE(message.find("rank 1"), std::string::npos) << "no message names rank 1:\n" << message;
  EXPECT_LT(last_logged_step(run), 6) << "the run went on to the end after the kill";
  std::cout << "mpirun ended " << seconds << " s after rank 1 was killed after step " << killed_after << "\n";

  // Resumed on two ranks: the same losses and, after every step, the same parameters.
  Mpirun second = start_mpirun(mpirun, config, data, run, true);
  const int resumed = wait_for(second.pid, 120);
  if (resumed == -1) ::kill(second.pid, SIGKILL), ::waitpid(second.pid, nullptr, 0);
  ASSERT_TRUE(resumed != -1 && WIFEXITED(resumed) && WEXITSTATUS(resumed) == 0)
      << "the resumed two-rank run failed:\n" << slurp(second.output);
  EXPECT_EQ(slurp(run / "losses.csv"), slurp(fs::path(o.run) / "losses.csv"));
  const std::string checksums = slurp(run / "parameters.csv");
  EXPECT_EQ(std::count(checksums.begin(), checksums.end(), '\n'), 7) << checksums;  // header and 6 steps
  EXPECT_EQ(checksums, slurp(fs::path(o.run) / "parameters.csv"));
  EXPECT_TRUE(fs::exists(run / "model.safetensors"));

  // A rank that hangs (SIGSTOP: alive, silent) ends the job once the other has waited
  // WEFT_MPI_TIMEOUT_S in a collective.
  const fs::path hung = root / "hung";
  Mpirun third = start_mpirun(mpirun, config, data, hung, false, "3");
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (last_logged_step(hung) < 1 && std::chrono::steady_clock::now() < until && wait_for(third.pid, 0.02) == -1) {
  }
  ASSERT_GE(last_logged_step(hung), 1) << slurp(third.output);
  const pid_t stopped = rank_pid(third.pid, 1);
  ASSERT_GT(stopped, 0);
  ::kill(stopped, SIGSTOP);
  const auto stopped_at = std::chrono::steady_clock::now();
  const int ended = wait_for(third.pid, 30);
  if (ended == -1) ::kill(stopped, SIGKILL), ::kill(third.pid, SIGKILL), ::waitpid(third.pid, nullptr, 0);
  ASSERT_NE(ended, -1) << "rank 1 was stopped and the job was still running 30 s later";
  const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - stopped_at).count();
  EXPECT_GE(waited, 2.5);
  EXPECT_NE(slurp(third.output).find("rank 0 of 2"), std::string::npos) << slurp(third.output);
  EXPECT_NE(slurp(third.output).find("waited 3 s in the collective"), std::string::npos) << slurp(third.output);
  std::cout << "mpirun ended " << waited << " s after rank 1 was stopped (timeout 3 s)\n";
}
