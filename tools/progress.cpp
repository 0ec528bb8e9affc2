#include "tools/progress.hpp"

#include <unistd.h>

#include <nlohmann/json.hpp>

#include "io/error.hpp"

namespace topotrack::cli {

ProgressMode parse_progress_mode(const std::string& s) {
  if (s == "auto") return ProgressMode::Auto;
  if (s == "bar") return ProgressMode::Bar;
  if (s == "lines") return ProgressMode::Lines;
  if (s == "jsonl") return ProgressMode::Jsonl;
  if (s == "quiet") return ProgressMode::Quiet;
  TT_THROW(UsageError, "--progress: unknown mode '" << s << "' (auto, bar, lines, jsonl, quiet)");
}

Progress::Progress(ProgressMode mode, std::size_t total, std::FILE* out)
    : mode_(mode), total_(total), out_(out), start_(std::chrono::steady_clock::now()) {
  if (mode_ == ProgressMode::Auto) mode_ = isatty(fileno(out_)) ? ProgressMode::Bar : ProgressMode::Lines;
}

double Progress::eta_seconds(std::size_t done) const {
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const std::size_t run = done > started_at_ ? done - started_at_ : 0;
  if (run == 0) return -1;
  return elapsed / double(run) * double(total_ - done);
}

void Progress::stage(std::size_t index, long number, const std::string& stage) {
  const std::lock_guard lock(mutex_);
  if (first_) {
    started_at_ = index;
    start_ = std::chrono::steady_clock::now();
    first_ = false;
  }
  if (mode_ == ProgressMode::Bar) {
    const int width = 30;
    const int filled = total_ ? int(double(index) / double(total_) * width) : 0;
    std::string bar(std::size_t(filled), '#');
    bar.resize(width, '.');
    const double eta = eta_seconds(index);
    char etabuf[32] = "--";
    if (eta >= 0) std::snprintf(etabuf, sizeof etabuf, "%.0fs", eta);
    std::fprintf(out_, "\r[%s] frame %zu/%zu (#%ld) %-18s ETA %-8s", bar.c_str(), index + 1, total_, number,
                 stage.c_str(), etabuf);
    std::fflush(out_);
  } else if (mode_ == ProgressMode::Jsonl) {
    std::fprintf(out_, "{\"event\":\"stage\",\"frame_index\":%zu,\"frame\":%ld,\"total\":%zu,\"stage\":\"%s\"}\n", index,
                 number, total_, stage.c_str());
    std::fflush(out_);
  }
}

void Progress::frame_done(std::size_t index, long number, const std::string& summary, const std::string& json) {
  const std::lock_guard lock(mutex_);
  if (first_) {
    started_at_ = index;
    first_ = false;
  }
  const double eta = eta_seconds(index + 1);
  if (mode_ == ProgressMode::Lines) {
    std::fprintf(out_, "frame %zu/%zu (#%ld) %s eta %.0fs\n", index + 1, total_, number, summary.c_str(),
                 eta < 0 ? 0.0 : eta);
  } else if (mode_ == ProgressMode::Jsonl) {
    std::fprintf(out_, "{\"event\":\"frame\",\"frame_index\":%zu,\"frame\":%ld,\"total\":%zu,\"eta_seconds\":%.3f,\"report\":%s}\n",
                 index, number, total_, eta < 0 ? 0.0 : eta, json.c_str());
  } else if (mode_ == ProgressMode::Bar && index + 1 == total_) {
    std::fprintf(out_, "\n");
  }
  std::fflush(out_);
}

void Progress::finish(const std::string& summary) {
  const std::lock_guard lock(mutex_);
  if (mode_ == ProgressMode::Quiet) return;
  if (mode_ == ProgressMode::Jsonl)
    std::fprintf(out_, "%s\n", nlohmann::json{{"event", "done"}, {"summary", summary}}.dump().c_str());
  else std::fprintf(out_, "%s\n", summary.c_str());
  std::fflush(out_);
}

void Progress::message(const std::string& text) {
  const std::lock_guard lock(mutex_);
  if (mode_ == ProgressMode::Quiet) return;
  if (mode_ == ProgressMode::Jsonl)
    std::fprintf(out_, "%s\n", nlohmann::json{{"event", "message"}, {"text", text}}.dump().c_str());
  else std::fprintf(out_, "%s%s\n", mode_ == ProgressMode::Bar ? "\n" : "", text.c_str());
  std::fflush(out_);
}

}  // namespace topotrack::cli
