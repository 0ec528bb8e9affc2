#pragma once
//! The subcommands of the `topotrack` CLI. Each lives in its own tools/cmd_<name>.cpp and registers
//! itself with a static TOPOTRACK_COMMAND(order, add_function); main() adds them in `order`.
#include <CLI/CLI.hpp>

namespace topotrack::cli {

using AddCommand = void (*)(CLI::App&);
//! Registers a subcommand; `order` fixes its place in `topotrack --help`.
struct CommandRegistrar {
  CommandRegistrar(int order, AddCommand add);
};
//! Add every registered subcommand to `app`, by order.
void add_all_commands(CLI::App& app);

}  // namespace topotrack::cli

#define TOPOTRACK_COMMAND(order, fn) \
  static const ::topotrack::cli::CommandRegistrar topotrack_command_registrar_##fn{order, fn}
