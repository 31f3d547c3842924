#include "tools/run/progress_reporter.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

namespace grove::tools {
namespace {

constexpr double kTerminalRedrawS = 0.1;
constexpr double kPlainIntervalS = 5.0;
constexpr int kBarWidth = 30;

double SteadyNow() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

std::string FormatRate(double per_s) {
  if (!std::isfinite(per_s) || per_s < 0.0) return "?";
  static constexpr struct {
    double scale;
    const char* suffix;
  } kUnits[] = {{1e12, "T"}, {1e9, "G"}, {1e6, "M"}, {1e3, "k"}};
  for (const auto& unit : kUnits) {
    double v = per_s / unit.scale;
    // Thresholds at the rounding points: 9.96M prints as "10M", 999.7k as "1.0M".
    if (v >= 9.95) return fmt::format("{:.0f}{}", v, unit.suffix);
    if (v >= 0.995) return fmt::format("{:.1f}{}", v, unit.suffix);
  }
  return fmt::format("{:.0f}", per_s);
}

std::string FormatClock(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0.0) return "--:--";
  int64_t s = std::llround(seconds);
  if (s >= 3600) return fmt::format("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60);
  return fmt::format("{}:{:02}", s / 60, s % 60);
}

std::string FormatDuration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0.0) return "?";
  int64_t s = std::llround(seconds);
  if (s < 60) return fmt::format("{} s", s);
  if (s < 3600) return fmt::format("{} min {} s", s / 60, s % 60);
  return fmt::format("{} h {:02} min", s / 3600, s / 60 % 60);
}

ProgressReporter::ProgressReporter(int64_t total_steps, int64_t particles, std::FILE* out,
                                   bool is_terminal, std::function<double()> now_s)
    : total_steps_(std::max<int64_t>(total_steps, 0)),
      particles_(std::max<int64_t>(particles, 0)),
      out_(out),
      is_terminal_(is_terminal),
      now_s_(now_s ? std::move(now_s) : std::function<double()>(SteadyNow)),
      start_s_(now_s_()),
      last_output_s_(start_s_) {}

double ProgressReporter::Now() const { return now_s_(); }

void ProgressReporter::Update(int64_t steps_done) {
  if (finished_) return;
  steps_done_ = std::clamp<int64_t>(steps_done, 0, total_steps_);
  double now = Now();
  if (is_terminal_) {
    if (drawn_ && now - last_output_s_ < kTerminalRedrawS) return;
    last_output_s_ = now;
    drawn_ = true;
    std::string line = TerminalLine(now);
    size_t chars = line.size();
    // Blank out what is left of a longer previous line.
    if (chars < last_line_chars_) line.append(last_line_chars_ - chars, ' ');
    last_line_chars_ = chars;
    Write("\r" + line);
    return;
  }
  // The line for the whole run comes from Finish().
  if (total_steps_ == 0 || steps_done_ == total_steps_) return;
  int64_t tenth = steps_done_ * 10 / total_steps_;
  if (tenth >= next_tenth_ || now - last_output_s_ >= kPlainIntervalS) {
    next_tenth_ = tenth + 1;
    last_output_s_ = now;
    Write(PlainLine(now) + "\n");
  }
}

void ProgressReporter::Finish() {
  if (finished_) return;
  finished_ = true;
  double elapsed = Now() - start_s_;
  double particle_steps = static_cast<double>(steps_done_) * static_cast<double>(particles_);
  int percent = total_steps_ == 0 ? 100 : static_cast<int>(steps_done_ * 100 / total_steps_);
  std::string rate = elapsed > 0.0 ? FormatRate(particle_steps / elapsed) : "?";
  std::string line = fmt::format(
      "done: step {}/{} ({}%), {} particle-steps in {}, {} particle-steps/s", steps_done_,
      total_steps_, percent, FormatRate(particle_steps), FormatDuration(elapsed), rate);
  if (is_terminal_ && drawn_) {
    if (line.size() < last_line_chars_) line.append(last_line_chars_ - line.size(), ' ');
    line = "\r" + line;
  }
  Write(line + "\n");
}

std::string ProgressReporter::TerminalLine(double now) const {
  double elapsed = now - start_s_;
  double fraction = total_steps_ == 0
                        ? 1.0
                        : static_cast<double>(steps_done_) / static_cast<double>(total_steps_);
  int filled = static_cast<int>(fraction * kBarWidth);
  std::string bar(static_cast<size_t>(filled), '#');
  bar.append(static_cast<size_t>(kBarWidth - filled), '.');
  std::string rate = "?";
  std::string eta = "--:--";
  if (elapsed > 0.0 && steps_done_ > 0) {
    double steps_per_s = steps_done_ / elapsed;
    rate = FormatRate(steps_per_s * static_cast<double>(particles_));
    eta = FormatClock((total_steps_ - steps_done_) / steps_per_s);
  }
  return fmt::format("[{}] {:3.0f}% steps {}/{}  {} p-steps/s  elapsed {}  ETA {}", bar,
                     std::floor(fraction * 100.0), steps_done_, total_steps_, rate,
                     FormatClock(elapsed), eta);
}

std::string ProgressReporter::PlainLine(double now) const {
  double elapsed = now - start_s_;
  int percent = static_cast<int>(steps_done_ * 100 / total_steps_);
  std::string rate = "?";
  std::string eta = "?";
  if (elapsed > 0.0 && steps_done_ > 0) {
    double steps_per_s = steps_done_ / elapsed;
    rate = FormatRate(steps_per_s * static_cast<double>(particles_));
    eta = FormatDuration((total_steps_ - steps_done_) / steps_per_s);
  }
  return fmt::format("step {}/{} ({}%) {} particle-steps/s, ETA {}", steps_done_, total_steps_,
                     percent, rate, eta);
}

void ProgressReporter::Write(const std::string& text) {
  if (out_ == nullptr) return;
  std::fwrite(text.data(), 1, text.size(), out_);
  std::fflush(out_);
}

}  // namespace grove::tools
