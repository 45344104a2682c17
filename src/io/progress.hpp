#pragma once
// A one-line progress display on stderr, redrawn in place with a carriage return.

#include <chrono>
#include <cstddef>

namespace kiln::io {

/// Shows simulated time, % done, steps/s, elapsed wall time and ETA on one stderr line, redrawn at
/// most about four times per second. Silent when disabled or when stderr is not a terminal.
class Progress {
  public:
    /// Progress towards simulated time `end_time` (s); `enabled` false keeps it silent.
    Progress(double end_time, bool enabled);
    /// Prints the final newline if anything was printed.
    ~Progress();
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;
    Progress(Progress&&) = delete;
    Progress& operator=(Progress&&) = delete;

    /// Reports simulated time `sim_time` (s) after `steps` steps of this run; cheap enough to call
    /// every step (the clock is read only every few calls, the stride adapts to the step cost).
    void update(double sim_time, long steps);

    /// Redraws the line with the last reported values and ends it with a newline, if anything was
    /// printed; later calls do nothing until update() prints again.
    void finish();

    /// True when the line is drawn (enabled and stderr is a terminal).
    [[nodiscard]] bool active() const { return enabled_; }

  private:
    using Clock = std::chrono::steady_clock;

    void draw(Clock::time_point now);

    double end_time_;
    bool enabled_;
    bool printed_ = false;
    bool started_ = false;
    double sim_last_ = 0;          // last reported simulated time (s)
    long steps_last_ = 0;          // last reported step count
    double sim_start_ = 0;         // simulated time at the first update (s)
    long steps_start_ = 0;         // step count at the first update
    Clock::time_point wall_start_; // wall time at the first update
    Clock::time_point last_check_; // wall time of the last clock read
    Clock::time_point last_draw_;  // wall time of the last redraw
    long countdown_ = 0;           // calls left before the next clock read
    long stride_ = 1;              // calls between clock reads
    std::size_t width_ = 0;        // length of the line last drawn (characters)
};

} // namespace kiln::io
