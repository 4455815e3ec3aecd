// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// The progress bar of the orient_normals program, in core and with --stream.

#ifndef NORMAL_ORIENTATION_EXAMPLES_CLI_PROGRESS_BAR_H
#define NORMAL_ORIENTATION_EXAMPLES_CLI_PROGRESS_BAR_H

#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>

namespace Cli {

/// \brief A one-line progress bar on stderr: the stage when there is one, then a
/// bar and a percentage, or a count when the size of the stage is unknown.
///
/// It is drawn only when enabled and stderr is a terminal, and only once the
/// run has lasted half a second; it is redrawn when the stage or the percentage
/// changes (a count at most every quarter of a second), and erased by
/// `finish()` or by the destructor (also when an error unwinds).
class Progress_bar
{
public:
  /// \brief A bar drawn when `enabled` and stderr is a terminal.
  explicit Progress_bar(bool enabled)
    : m_enabled(enabled && isatty(2) == 1), m_start(std::chrono::steady_clock::now())
  {}
  ~Progress_bar() { finish(); }
  Progress_bar(const Progress_bar&) = delete;
  Progress_bar& operator=(const Progress_bar&) = delete;

  /// \brief Shows `fraction` (in [0, 1]) of a run without stages; returns
  /// `true` (go on), as a `callback` of `orient_normals()` must.
  bool operator()(double fraction) { return update("", fraction, 0); }

  /// \brief Shows the stage `stage` with `fraction` (in [0, 1]) done, or, when
  /// `fraction` is negative (size unknown), `done` points; returns `true`.
  bool update(const std::string& stage, double fraction, std::uint64_t done)
  {
    if (!m_enabled)
      return true;
    const auto now = std::chrono::steady_clock::now();
    if (seconds(m_start, now) < 0.5)
      return true;
    const int percent = fraction >= 0.0 ? int(fraction * 100.0) : -1;
    if (m_drawn_once && stage == m_stage && percent == m_percent &&
        (percent >= 0 || seconds(m_drawn_at, now) < 0.25))
      return true;
    m_drawn_once = true;
    m_stage = stage;
    m_percent = percent;
    m_drawn_at = now;
    std::string line;
    if (!stage.empty()) { // the stage, left-aligned on 10 columns
      line = stage;
      if (line.size() < 10)
        line.resize(10, ' ');
      line += ' ';
    }
    if (percent >= 0) {
      const int width = 40, filled = percent * width / 100;
      char tail[16];
      std::snprintf(tail, sizeof tail, "] %3d%%", percent);
      line += "[" + std::string(std::size_t(filled), '#') + std::string(std::size_t(width - filled), ' ') + tail;
    } else
      line += std::to_string(done) + " points";
    std::fprintf(stderr, "\r%-60s", line.c_str());
    m_visible = true;
    return true;
  }

  /// \brief Erases the bar, if it is drawn.
  void finish()
  {
    if (m_visible)
      std::fprintf(stderr, "\r%60s\r", "");
    m_visible = false;
  }

private:
  static double seconds(std::chrono::steady_clock::time_point from, std::chrono::steady_clock::time_point to)
  {
    return std::chrono::duration<double>(to - from).count();
  }

  bool m_enabled;
  std::chrono::steady_clock::time_point m_start, m_drawn_at;
  std::string m_stage;
  int m_percent = -2;
  bool m_drawn_once = false; // m_stage and m_percent hold what was drawn last
  bool m_visible = false;    // the bar is on the terminal
};

} // namespace Cli

#endif // NORMAL_ORIENTATION_EXAMPLES_CLI_PROGRESS_BAR_H
