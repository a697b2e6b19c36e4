#pragma once
// Progress of a long run on stderr. On a terminal: one line redrawn in place with a bar, steps/s
// and the time left, at most 10 times a second (and at the last step): a redraw per step would
// cost a write to the terminal per step. Otherwise (logs, CI): a plain line every 10 %. Debian
// packages no C++ progress bar library, so this small one lives here.

#include <chrono>
#include <string>

namespace torsion::cli {

class ProgressBar {
 public:
  explicit ProgressBar(std::string label);
  void update(int done, int total, double rate);
  /// Ends the line (on a terminal).
  void finish();

 private:
  std::string label_;
  bool terminal_;
  int last_decile_ = -1;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point last_drawn_{};
};

}  // namespace torsion::cli
