#include "tools/commands.hpp"

#include <algorithm>
#include <utility>
#include <vector>

namespace topotrack::cli {
namespace {
std::vector<std::pair<int, AddCommand>>& registry() {
  static std::vector<std::pair<int, AddCommand>> r;
  return r;
}
}  // namespace

CommandRegistrar::CommandRegistrar(int order, AddCommand add) { registry().emplace_back(order, add); }

void add_all_commands(CLI::App& app) {
  auto r = registry();
  std::stable_sort(r.begin(), r.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [order, add] : r) add(app);
}

}  // namespace topotrack::cli
