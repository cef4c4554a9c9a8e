#include "tools/fmpc/progress_line.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>

namespace fmpc::cli {

namespace {

// FMPC_PROGRESS_SECONDS, when it is a positive number (at least 0.01 s); else 10 s.
double pipe_period() {
  const char* text = std::getenv("FMPC_PROGRESS_SECONDS");
  if (text == nullptr) return 10.0;
  char* end = nullptr;
  const double seconds = std::strtod(text, &end);
  return end != text && *end == '\0' && seconds >= 0.01 && std::isfinite(seconds) ? seconds : 10.0;
}

// "350", "2.5", "3.42e+10": whole counts as they are up to a million, the rest to three digits.
std::string count_text(double value) {
  if (value == std::floor(value) && value < 1e6) return std::to_string(static_cast<long long>(value));
  char text[32];
  std::snprintf(text, sizeof text, value < 1e6 ? "%.1f" : "%.3g", value);
  return text;
}

}  // namespace

ProgressLine::ProgressLine(std::string command)
    : command_(std::move(command)),
      terminal_(::isatty(STDERR_FILENO) == 1),
      period_(pipe_period()),
      next_line_(terminal_ ? 1.0 : period_),
      start_(std::chrono::steady_clock::now()) {}

double ProgressLine::elapsed_seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

bool ProgressLine::due() {
  const double elapsed = elapsed_seconds();
  if (elapsed < next_line_) return false;
  if (!terminal_) next_line_ = elapsed + period_;
  return true;
}

void ProgressLine::show(const std::string& text) {
  if (!due()) return;
  if (!terminal_) {
    std::cerr << "fmpc " << command_ << ": progress: " << text << std::endl;
    return;
  }
  std::string line = "fmpc " + command_ + ": " + text;
  const std::size_t width = line.size();
  if (width < drawn_width_) line += std::string(drawn_width_ - width, ' ');
  std::cerr << '\r' << line << std::flush;
  drawn_width_ = width;
}

void ProgressLine::show_fraction(double done, double total, const std::string& unit) {
  if (!(total > 0.0) || elapsed_seconds() < next_line_) return;
  const double fraction = std::min(1.0, std::max(0.0, done / total));
  std::string text = std::to_string(static_cast<int>(100 * fraction)) + "% " + unit + " " + count_text(done) + "/" +
                     count_text(total);
  if (terminal_) {
    const int width = 30;
    const int filled = static_cast<int>(width * fraction);
    text = "[" + std::string(static_cast<std::size_t>(filled), '#') +
           std::string(static_cast<std::size_t>(width - filled), '.') + "] " + text;
  }
  const double elapsed = elapsed_seconds();
  if (fraction > 0.0 && fraction < 1.0) text += ", about " + duration_text(elapsed / fraction - elapsed) + " left";
  show(text);
}

void ProgressLine::finish() {
  if (drawn_width_ > 0) std::cerr << '\r' << std::string(drawn_width_, ' ') << '\r' << std::flush;
  drawn_width_ = 0;
}

std::string duration_text(double seconds) {
  if (!(seconds >= 0) || !std::isfinite(seconds)) return "unknown time";
  const long s = std::lround(seconds);
  if (s < 60) return std::to_string(s) + " s";
  if (s < 3600) return std::to_string(s / 60) + " min " + std::to_string(s % 60) + " s";
  return std::to_string(s / 3600) + " h " + std::to_string((s % 3600) / 60) + " min";
}

}  // namespace fmpc::cli
