#pragma once
// Progress of a command that can take more than a second (simulate, compile --target table, trade, plot, eval,
// convert, thesis-benchmark; docs/cli.md), with an estimate of the time left, on stderr:
// - on a terminal, one line redrawn in place once a second has passed, erased at the end;
// - on a pipe or a file, a plain line every FMPC_PROGRESS_SECONDS seconds (default 10; the first after that long),
//   starting "fmpc COMMAND: progress: ", left in place: logs keep them, and a run shorter than the period prints
//   none (the golden tests drop such lines before comparing).
#include <chrono>
#include <cstddef>
#include <string>

namespace fmpc::cli {

class ProgressLine {
 public:
  explicit ProgressLine(std::string command);
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;
  ~ProgressLine() { finish(); }

  double elapsed_seconds() const;
  // "fmpc COMMAND: TEXT" (on a pipe "fmpc COMMAND: progress: TEXT"), when it is time to show one.
  void show(const std::string& text);
  // `done` of `total` (a bar on a terminal) and the time left at the rate so far (an estimate); `unit` names what
  // is counted ("step", "row"). Fractions of a unit count: 2.5 of 18 runs.
  void show_fraction(double done, double total, const std::string& unit);
  void show_fraction(std::size_t done, std::size_t total, const std::string& unit) {
    show_fraction(static_cast<double>(done), static_cast<double>(total), unit);
  }
  void finish();

 private:
  bool due();  // whether a line is to be drawn now

  std::string command_;
  bool terminal_;
  double period_;      // seconds between plain lines on a pipe
  double next_line_;   // elapsed seconds at which the next plain line is due
  std::size_t drawn_width_ = 0;
  std::chrono::steady_clock::time_point start_;
};

// "12 s", "3 min 20 s", "1 h 5 min": a duration for people.
std::string duration_text(double seconds);

}  // namespace fmpc::cli
