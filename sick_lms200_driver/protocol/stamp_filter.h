// Removes host-side delays from first-beam stamps.
//
// A raw estimate (arrival of the last byte − transmission − sweep) can only
// be late, never early: the reading thread may be scheduled late and USB
// adapters hold bytes for up to their latency timer. The sensor, however,
// starts each scan on a mirror-turn boundary, so consecutive true stamps
// differ by a whole number n of mirror periods T. The filter keeps the lower
// envelope: predicted = previous + n·T, stamp = min(raw, predicted + slack),
// where the slack (a fraction of the elapsed time) lets it follow a sensor
// whose mirror runs slower than nominal. Delays must stay below half a mirror
// period (6.7 ms) to be attributed to the right turn; three raw estimates in
// a row more than `max_delay` after the prediction (a clock jump, or a real
// change) restart the filter from the raw value.
#pragma once

namespace sick_lms200 {

class StampFilter {
 public:
  // period: nominal mirror period (s); drift: relative slack (e.g. 1e-3);
  // max_delay: largest host delay the filter removes (s).
  StampFilter(double period, double drift = 1e-3, double max_delay = 0.005)
      : period_(period), drift_(drift), max_delay_(max_delay) {}

  double filter(double raw) {
    if (!initialised_) return restart(raw);
    const double elapsed = raw - last_;
    if (elapsed <= 0.0 || elapsed > 2.0) return restart(raw);  // time went back, or a gap
    const double turns = static_cast<double>(static_cast<long>(elapsed / period_ + 0.5));
    const double predicted = last_ + turns * period_ + drift_ * elapsed;
    if (raw <= predicted) {
      outliers_ = 0;
      return last_ = raw;  // at least as early as predicted: the better estimate
    }
    if (raw - predicted > max_delay_ && ++outliers_ >= 3) return restart(raw);
    if (raw - predicted <= max_delay_) outliers_ = 0;
    return last_ = predicted;
  }
  void reset() { initialised_ = false; }

 private:
  double restart(double raw) {
    initialised_ = true;
    outliers_ = 0;
    last_ = raw;
    return raw;
  }

  double period_;
  double drift_;
  double max_delay_;
  bool initialised_ = false;
  double last_ = 0.0;
  int outliers_ = 0;
};

}  // namespace sick_lms200
