#pragma once
// One function per `weft` subcommand, each in its own apps/<name>.cpp: it declares the
// subcommand's options on `app` and its callback runs the library code.
#include <CLI/CLI.hpp>

namespace weft::apps {

void add_ops_command(CLI::App& app);
void add_engine_check_command(CLI::App& app);
void add_sim_command(CLI::App& app);
void add_pose_command(CLI::App& app);
void add_character_command(CLI::App& app);
void add_nn_command(CLI::App& app);
void add_bench_command(CLI::App& app);
void add_synth_command(CLI::App& app);
void add_train_command(CLI::App& app);
void add_infer_command(CLI::App& app);
void add_detect_command(CLI::App& app);
void add_adapt_command(CLI::App& app);
void add_eval_command(CLI::App& app);

}  // namespace weft::apps
