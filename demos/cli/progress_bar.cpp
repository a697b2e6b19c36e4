#include "progress_bar.h"

#include <unistd.h>

#include <cstdio>

namespace torsion::cli {

ProgressBar::ProgressBar(std::string label)
    : label_(std::move(label)), terminal_(isatty(STDERR_FILENO) != 0) {}

void ProgressBar::update(int done, int total, double rate) {
  const double fraction = total > 0 ? double(done) / total : 1.0;
  const double eta = rate > 0 ? (total - done) / rate : 0.0;
  if (terminal_) {
    const auto now = std::chrono::steady_clock::now();
    if (drawn_ && done < total && now - last_drawn_ < std::chrono::milliseconds(100)) return;
    last_drawn_ = now;
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(fraction * kWidth);
    std::string bar(static_cast<size_t>(filled), '=');
    if (filled < kWidth) bar += '>';
    bar.resize(kWidth, ' ');
    std::fprintf(stderr, "\r%s [%s] %d/%d steps  %.1f steps/s  %.0f s left ", label_.c_str(),
                 bar.c_str(), done, total, rate, eta);
    std::fflush(stderr);
    drawn_ = true;
  } else {
    const int decile = static_cast<int>(fraction * 10);
    if (decile != last_decile_) {
      last_decile_ = decile;
      std::fprintf(stderr, "%s: step %d/%d (%d%%), %.1f steps/s\n", label_.c_str(), done, total,
                   decile * 10, rate);
    }
  }
}

void ProgressBar::finish() {
  if (terminal_ && drawn_) std::fprintf(stderr, "\n");
}

}  // namespace torsion::cli
