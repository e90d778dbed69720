#include "app/sweep_progress.hpp"

#include "kernel/params.hpp"

#include <cmath>
#include <cstdio>
#include <iomanip>
#include <ostream>

#include "app/sweep_spec.hpp"

namespace tbdr {

namespace {

std::string format_duration(double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  const long t = std::lround(s);
  char buf[32];
  if (t >= 3600) {
    std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
  } else {
    std::snprintf(buf, sizeof buf, "%ld:%02ld", t / 60, t % 60);
  }
  return buf;
}

std::string first_line(const std::string& s) {
  std::string t = trim(s);
  const auto nl = t.find('\n');
  return nl == std::string::npos ? t : t.substr(0, nl) + " ...";
}

}  // namespace

SweepProgressDisplay::SweepProgressDisplay(SweepProgress mode, std::ostream& out, std::size_t total,
                                           std::size_t skipped)
    : mode_(mode), out_(out), total_(total), done_(skipped), start_(std::chrono::steady_clock::now()) {}

void SweepProgressDisplay::finished(const SweepPoint& p, bool ok, double seconds, const std::string& error) {
  ++done_;
  ++ran_;
  if (!ok) ++failed_;
  if (mode_ == SweepProgress::None) return;
  if (mode_ == SweepProgress::Bar) {
    if (!ok) {
      clear_bar();
      out_ << "FAILED " << p.label << ": " << first_line(error) << "\n";
    }
    draw(true);
    return;
  }
  char head[64];
  std::snprintf(head, sizeof head, "[%*zu/%zu] ", static_cast<int>(std::to_string(total_).size()), done_, total_);
  out_ << head << (ok ? "ok     " : "FAILED ") << std::fixed << std::setprecision(2) << seconds << " s  " << p.label;
  out_ << "  (" << rate_text() << ", ETA " << eta_text() << ")";
  if (!ok) out_ << "\n    " << first_line(error);
  out_ << "\n" << std::flush;
}

void SweepProgressDisplay::skipped() {
  ++done_;
  draw(true);
}

void SweepProgressDisplay::message(const std::string& text) {
  if (mode_ == SweepProgress::None) return;
  clear_bar();
  out_ << text << "\n" << std::flush;  // "stopping: ..." must show while the workers finish
  draw(true);
}

void SweepProgressDisplay::set_running(std::size_t running) { running_ = running; }

void SweepProgressDisplay::draw(bool force) {
  if (mode_ != SweepProgress::Bar) return;
  const auto now = std::chrono::steady_clock::now();
  if (!force && now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  constexpr int kWidth = 30;
  const double frac = total_ ? static_cast<double>(done_) / static_cast<double>(total_) : 1.0;
  const int filled = static_cast<int>(frac * kWidth);
  std::string bar(static_cast<std::size_t>(filled), '#');
  bar += std::string(static_cast<std::size_t>(kWidth - filled), '.');
  out_ << "\r\033[K[" << bar << "] " << done_ << "/" << total_;
  if (failed_) out_ << "  " << failed_ << " failed";
  out_ << "  " << running_ << " running  " << rate_text() << "  ETA " << eta_text() << std::flush;
  drawn_ = true;
}

void SweepProgressDisplay::end() {
  if (mode_ == SweepProgress::Bar && drawn_) {
    draw(true);
    out_ << "\n";
    drawn_ = false;
  }
}

double SweepProgressDisplay::elapsed() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

std::string SweepProgressDisplay::rate_text() const {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.2f points/s", ran_ ? static_cast<double>(ran_) / elapsed() : 0.0);
  return buf;
}

std::string SweepProgressDisplay::eta_text() const {
  if (!ran_) return "?";
  const double rate = static_cast<double>(ran_) / elapsed();
  return format_duration(static_cast<double>(total_ - done_) / rate);
}

void SweepProgressDisplay::clear_bar() {
  if (mode_ == SweepProgress::Bar && drawn_) out_ << "\r\033[K";
}

}  // namespace tbdr
