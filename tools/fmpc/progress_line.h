#pragma once
// One line of progress on stderr for commands that can take more than a second (simulate, compile --target table,
// trade): drawn only on a terminal, only once a second has passed, redrawn in place and erased at the end, so that
// pipes, logs and the golden tests see nothing of it.
#include <chrono>
#include <string>

namespace fmpc::cli {

class ProgressLine {
 public:
  explicit ProgressLine(std::string command);
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;
  ~ProgressLine() { finish(); }

  double elapsed_seconds() const;
  // Redraws the line as "fmpc COMMAND: TEXT".
  void show(const std::string& text);
  // A bar for `done` of `total` steps with the time left at the rate so far (an estimate).
  void show_fraction(std::size_t done, std::size_t total, const std::string& unit);
  void finish();

 private:
  std::string command_;
  bool enabled_;
  std::size_t drawn_width_ = 0;
  std::chrono::steady_clock::time_point start_;
};

// "12 s", "3 min 20 s", "1 h 5 min": a duration for people.
std::string duration_text(double seconds);

}  // namespace fmpc::cli
