#include "tools/fmpc/progress_line.h"

#include <unistd.h>

#include <cmath>
#include <iostream>

namespace fmpc::cli {

ProgressLine::ProgressLine(std::string command)
    : command_(std::move(command)), enabled_(::isatty(STDERR_FILENO) == 1), start_(std::chrono::steady_clock::now()) {}

double ProgressLine::elapsed_seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void ProgressLine::show(const std::string& text) {
  if (!enabled_ || elapsed_seconds() < 1.0) return;
  std::string line = "fmpc " + command_ + ": " + text;
  const std::size_t width = line.size();
  if (width < drawn_width_) line += std::string(drawn_width_ - width, ' ');
  std::cerr << '\r' << line << std::flush;
  drawn_width_ = width;
}

void ProgressLine::show_fraction(std::size_t done, std::size_t total, const std::string& unit) {
  if (!enabled_ || total == 0) return;
  const double fraction = static_cast<double>(done) / static_cast<double>(total);
  const int width = 30;
  const int filled = static_cast<int>(width * fraction);
  std::string text = "[" + std::string(static_cast<std::size_t>(filled), '#') +
                     std::string(static_cast<std::size_t>(width - filled), '.') + "] " +
                     std::to_string(static_cast<int>(100 * fraction)) + "% " + unit + " " + std::to_string(done) +
                     "/" + std::to_string(total);
  const double elapsed = elapsed_seconds();
  if (done > 0 && done < total)
    text += ", about " + duration_text(elapsed / fraction - elapsed) + " left";
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
