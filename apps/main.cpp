// The `weft` command line: one subcommand per file in apps/.
#include <spdlog/spdlog.h>

#include <iostream>

#include "apps/commands.h"
#include "graph/error.h"
#include "graph/profiler.h"
#include "graph/threads.h"
#include "ops/conv_backend.h"

int main(int argc, char** argv) {
  CLI::App app{
      "weft: physics-aware monocular human performance capture on the CPU.\n"
      "Run `weft <command> --help` for a command's options."};
  app.require_subcommand(1);
  weft::num_threads();  // applies WEFT_NUM_THREADS before any parallel work
  int threads = 0;
  app.add_option("--threads", threads, "Thread budget for OpenMP and TBB (0: all cores; "
                                       "also WEFT_NUM_THREADS)");
  std::string conv_backend;
  app.add_option("--conv-backend", conv_backend,
                 "float32 convolution kernels: onednn (default, PyTorch's), eigen (weft's own, "
                 "more accurate, slower) or onednn-winograd (faster 3x3, less accurate); also "
                 "WEFT_CONV_BACKEND")
      ->check(CLI::IsMember({"eigen", "onednn", "onednn-winograd"}));
  app.set_version_flag("--version", "weft 0.1.0");
  app.parse_complete_callback([&] {
    if (threads > 0) weft::set_num_threads(threads);
    if (!conv_backend.empty())
      weft::set_conv_backend(weft::parse_conv_backend(conv_backend, "--conv-backend"));
  });
  weft::apps::add_ops_command(app);
  weft::apps::add_engine_check_command(app);
  weft::apps::add_sim_command(app);
  weft::apps::add_pose_command(app);
  weft::apps::add_character_command(app);
  weft::apps::add_synth_command(app);
  weft::apps::add_train_command(app);
  weft::apps::add_infer_command(app);
  weft::apps::add_detect_command(app);
  weft::apps::add_adapt_command(app);
  weft::apps::add_eval_command(app);
  weft::apps::add_nn_command(app);
  weft::apps::add_bench_command(app);
  // WEFT_PROFILE=1: the per-op time table goes to stderr when the command ends.
  struct ProfileAtExit {
    ~ProfileAtExit() {
      if (weft::profiling_enabled()) std::cerr << weft::profile_report();
    }
  } profile_at_exit;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const weft::Error& e) {
    spdlog::error("{}", e.what());
    return 1;
  } catch (const std::exception& e) {
    spdlog::error("unexpected error: {}", e.what());
    return 1;
  }
  return 0;
}
