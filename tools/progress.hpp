#pragma once
//! Progress display for long runs: a bar on a terminal (frame k/N, stage, ETA), plain lines when not
//! a terminal, JSON lines for host applications, or nothing.
#include <chrono>
#include <cstdio>
#include <mutex>
#include <string>

namespace topotrack::cli {

enum class ProgressMode { Auto, Bar, Lines, Jsonl, Quiet };

//! Parses "auto", "bar", "lines", "jsonl", "quiet". \throw UsageError
ProgressMode parse_progress_mode(const std::string& s);

//! Thread-safe: every call is one whole line (or bar update) under a lock.
class Progress {
public:
  Progress(ProgressMode mode, std::size_t total_frames, std::FILE* out = stderr);
  //! Frame `done` of `total` is being processed and is in `stage`.
  void stage(std::size_t frame_index, long frame_number, const std::string& stage);
  //! Frame finished; `summary` is a short human line, `json` a one-line JSON object (jsonl mode: the
  //! frame line's "report" member).
  void frame_done(std::size_t frame_index, long frame_number, const std::string& summary, const std::string& json);
  void finish(const std::string& summary);
  void message(const std::string& text);

private:
  double eta_seconds(std::size_t done) const;
  ProgressMode mode_;
  std::size_t total_;
  std::FILE* out_;
  std::chrono::steady_clock::time_point start_;
  std::size_t started_at_ = 0;  // frames already done before this run (resume)
  bool first_ = true;
  std::mutex mutex_;
};

}  // namespace topotrack::cli
