// `weft ops`: lists every registered op and whether it is differentiable.
#include <iomanip>
#include <iostream>

#include "apps/commands.h"
#include "graph/op_registry.h"

namespace weft::apps {

void add_ops_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("ops", "List the registered ops of the autodiff engine");
  cmd->callback([] {
    const auto ops = OpRegistry::instance().all();
    size_t differentiable = 0;
    std::cout << std::left << std::setw(24) << "op" << std::setw(8) << "grad"
              << "description\n";
    for (const OpDef* op : ops) {
      differentiable += op->differentiable;
      std::cout << std::left << std::setw(24) << op->name << std::setw(8)
                << (op->differentiable ? "yes" : "no") << op->doc << '\n';
    }
    std::cout << ops.size() << " ops, " << differentiable << " differentiable\n";
  });
}

}  // namespace weft::apps
