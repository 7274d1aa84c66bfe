// `weft demo`: a short tour of what exists.
#include <iostream>

#include "apps/commands.h"
#include "graph/op_registry.h"

namespace weft::apps {

void add_demo_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("demo", "Run a small end-to-end demo of weft");
  cmd->callback([] { std::cout << OpRegistry::instance().all().size() << " ops registered\n"; });
}

}  // namespace weft::apps
