// topotrack: temporally coherent triangle meshes from surface sequences with evolving topology.
// Exit codes: 0 ok, 1 runtime error, 2 usage, 3 invalid input.
#include <iostream>

#include "io/error.hpp"
#include "tools/commands.hpp"

int main(int argc, char** argv) {
  using namespace topotrack;
  CLI::App app{"topotrack: one temporally coherent deforming triangle mesh from a sequence of closed surfaces "
               "whose topology changes (Bojsen-Hansen, Li, Wojtan 2012).",
               "topotrack"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("topotrack ") + TOPOTRACK_VERSION);
  cli::add_all_commands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitUsage;
  } catch (const Error& e) {
    std::cerr << "topotrack: error: " << e.what() << "\n";
    return exit_code_for(e);
  } catch (const std::bad_alloc&) {
    std::cerr << "topotrack: error: out of memory\n";
    return kExitRuntime;
  } catch (const std::exception& e) {
    std::cerr << "topotrack: internal error: " << e.what() << "\n";
    return kExitRuntime;
  }
  return kExitOk;
}
