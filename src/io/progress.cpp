#include "io/progress.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fmt/format.h>
#include <limits>
#include <string>
#include <unistd.h>

namespace kiln::io {

namespace {

/// Shortest interval between redraws (s): about four per second.
constexpr double redraw_interval = 0.25;
/// Clock reads closer together than this (s) double the stride; farther apart than the upper
/// bound halve it, so the clock is read every 10 to 50 ms whatever a step costs.
constexpr double check_min = 0.01;
constexpr double check_max = 0.05;
/// Largest stride between clock reads (calls).
constexpr long stride_max = 1L << 20;

/// `seconds` as h:mm:ss, or "--:--:--" when unknown.
std::string hms(double seconds) {
    constexpr double longest = 1e9; // beyond this an ETA means nothing (s)
    if (!std::isfinite(seconds) || seconds < 0.0 || seconds > longest) {
        return "--:--:--";
    }
    const auto s = std::llround(seconds);
    return fmt::format("{}:{:02}:{:02}", s / 3600, (s / 60) % 60, s % 60);
}

} // namespace

Progress::Progress(double end_time, bool enabled)
    : end_time_(end_time), enabled_(enabled && isatty(STDERR_FILENO) == 1) {
}

Progress::~Progress() {
    finish();
}

void Progress::update(double sim_time, long steps) {
    if (!enabled_) {
        return;
    }
    sim_last_ = sim_time;
    steps_last_ = steps;
    if (--countdown_ > 0) {
        return;
    }
    const Clock::time_point now = Clock::now();
    if (!started_) {
        started_ = true;
        sim_start_ = sim_time;
        steps_start_ = steps;
        wall_start_ = last_check_ = last_draw_ = now;
    }
    const double since_check = std::chrono::duration<double>(now - last_check_).count();
    if (since_check < check_min) {
        stride_ = std::min(2 * stride_, stride_max);
    } else if (since_check > check_max && stride_ > 1) {
        stride_ /= 2;
    }
    countdown_ = stride_;
    last_check_ = now;
    if (!printed_ || std::chrono::duration<double>(now - last_draw_).count() >= redraw_interval) {
        draw(now);
    }
}

void Progress::finish() {
    if (!printed_) {
        return;
    }
    draw(Clock::now());
    std::fputs("\n", stderr);
    std::fflush(stderr);
    printed_ = false;
    width_ = 0;
}

void Progress::draw(Clock::time_point now) {
    const double wall = std::chrono::duration<double>(now - wall_start_).count();
    const double sim_done = sim_last_ - sim_start_;
    const double percent = end_time_ > 0.0 ? 100.0 * std::min(sim_last_ / end_time_, 1.0) : 100.0;
    const double rate = wall > 0.0 ? static_cast<double>(steps_last_ - steps_start_) / wall : 0.0;
    const double eta = sim_done > 0.0 ? std::max(end_time_ - sim_last_, 0.0) * wall / sim_done
                                      : std::numeric_limits<double>::quiet_NaN();
    std::string line = fmt::format("t = {:.4e} s  {:5.1f} %  {:.3g} steps/s  elapsed {}  ETA {}",
                                   sim_last_, percent, rate, hms(wall), hms(eta));
    const std::size_t width = line.size();
    if (width < width_) {
        line.append(width_ - width, ' '); // wipe the tail of a longer previous line
    }
    width_ = width;
    std::fputs(("\r" + line).c_str(), stderr);
    std::fflush(stderr);
    printed_ = true;
    last_draw_ = now;
}

} // namespace kiln::io
