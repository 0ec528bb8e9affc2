// topotrack events FILE [--json] [--expand] [--summary]: print an event-list file (§4.4): counts by kind,
// then each event with V_in, V_out and its forward and backward rules.
#include <charconv>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "io/event_file.hpp"
#include "kernels/propagate/propagate.hpp"
#include "tools/commands.hpp"

namespace topotrack::cli {
namespace {

struct EventsOptions {
  std::string file;
  bool json = false;
  bool expand = false;
  bool summary = false;
};

// A rule as printed: target and terms, stored or expanded.
struct PrintedRule {
  VertexId target;
  std::vector<RuleTerm> terms;
};

std::vector<PrintedRule> rules_of(const EventList& list, std::size_t e, bool forward, bool expand) {
  std::vector<PrintedRule> out;
  if (expand) {
    for (ExpandedRule& r : expand_rules(list, e, forward)) out.push_back({r.target, std::move(r.terms)});
    return out;
  }
  const EventList::View v = list.event(e);
  const std::size_t b = forward ? v.forward_begin : v.backward_begin;
  const std::size_t end = forward ? v.forward_end : v.backward_end;
  for (std::size_t r = b; r < end; ++r) {
    const EventList::Rule rule = list.rule(r);
    out.push_back({rule.target, std::vector<RuleTerm>(rule.terms.begin(), rule.terms.end())});
  }
  return out;
}

void append_number(std::string& s, double w) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, w);
  s.append(buf, r.ptr);
}

void append_ids(std::string& s, std::span<const VertexId> ids) {
  for (VertexId id : ids) s.append(" ").append(std::to_string(id));
  if (ids.empty()) s += " -";
}

void append_rules(std::string& s, const char* label, const std::vector<PrintedRule>& rules) {
  if (rules.empty()) {
    s.append("  ").append(label).append(": -\n");
    return;
  }
  for (const PrintedRule& r : rules) {
    s.append("  ").append(label).append(": ").append(std::to_string(r.target)).append(" <-");
    for (std::size_t k = 0; k < r.terms.size(); ++k) {
      s.append(k ? " + " : " ");
      append_number(s, r.terms[k].weight);
      s.append(" * ").append(std::to_string(r.terms[k].source));
    }
    s += '\n';
  }
}

nlohmann::json rules_json(const std::vector<PrintedRule>& rules) {
  nlohmann::json a = nlohmann::json::array();
  for (const PrintedRule& r : rules) {
    nlohmann::json terms = nlohmann::json::array();
    for (const RuleTerm& t : r.terms) terms.push_back({t.source, t.weight});
    a.push_back({{"target", r.target}, {"terms", terms}});
  }
  return a;
}

void run_events(const EventsOptions& opt) {
  const EventList list = read_events(opt.file);
  const std::vector<std::size_t> counts = list.count_by_kind();
  if (opt.json) {
    nlohmann::json j;
    j["file"] = opt.file;
    j["events"] = list.size();
    j["rules"] = list.rule_count();
    j["terms"] = list.term_count();
    nlohmann::json by_kind;
    for (int k = 0; k < kEventKindCount; ++k)
      by_kind[std::string(to_string(static_cast<EventKind>(k + 1)))] = counts[k];
    j["counts"] = by_kind;
    if (!opt.summary) {
      j["expanded"] = opt.expand;
      nlohmann::json all = nlohmann::json::array();
      for (std::size_t e = 0; e < list.size(); ++e) {
        const EventList::View v = list.event(e);
        all.push_back({{"kind", std::string(to_string(v.kind))},
                       {"in", std::vector<VertexId>(v.in.begin(), v.in.end())},
                       {"out", std::vector<VertexId>(v.out.begin(), v.out.end())},
                       {"forward", rules_json(rules_of(list, e, true, opt.expand))},
                       {"backward", rules_json(rules_of(list, e, false, opt.expand))}});
      }
      j["list"] = std::move(all);
    }
    std::cout << j.dump(2) << "\n";
    return;
  }
  std::string s = "file: " + opt.file + "\nevents: " + std::to_string(list.size()) + " (";
  for (int k = 0; k < kEventKindCount; ++k) {
    if (k) s += ", ";
    s.append(to_string(static_cast<EventKind>(k + 1))).append(" ").append(std::to_string(counts[k]));
  }
  s.append(")\nrules: ").append(std::to_string(list.rule_count()));
  s.append("  terms: ").append(std::to_string(list.term_count())).append("\n");
  std::fwrite(s.data(), 1, s.size(), stdout);
  if (opt.summary) return;
  for (std::size_t e = 0; e < list.size(); ++e) {
    const EventList::View v = list.event(e);
    s.assign("event ").append(std::to_string(e)).append(" ").append(to_string(v.kind)).append("\n  V_in:");
    append_ids(s, v.in);
    s += "\n  V_out:";
    append_ids(s, v.out);
    s += '\n';
    append_rules(s, opt.expand ? "f (expanded)" : "f", rules_of(list, e, true, opt.expand));
    append_rules(s, opt.expand ? "b (expanded)" : "b", rules_of(list, e, false, opt.expand));
    std::fwrite(s.data(), 1, s.size(), stdout);
  }
}

void add_events_command(CLI::App& app) {
  auto opt = std::make_shared<EventsOptions>();
  CLI::App* sub = app.add_subcommand("events",
                                     "Print an event-list file (§4.4): counts by kind, then every event "
                                     "with V_in, V_out, forward and backward rules");
  sub->add_option("FILE", opt->file, "event-list file (docs/formats.md)")->required();
  sub->add_flag("--json", opt->json, "machine-readable JSON instead of text");
  sub->add_flag(
      "--expand", opt->expand,
      "print each rule in terms of vertices the event does not create (substituting earlier rules)");
  sub->add_flag("--summary", opt->summary, "print only the counts");
  sub->callback([opt] { run_events(*opt); });
}

}  // namespace

TOPOTRACK_COMMAND(40, add_events_command);

}  // namespace topotrack::cli
