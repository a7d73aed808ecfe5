// The distribution of a per-scan duration over a whole run, in constant
// memory: counts in 0.1 ms bins up to 10 s (longer ones in the last bin),
// for the percentiles /diagnostics reports.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>

namespace ekf_slam {

class ProcessingTimes {
 public:
  void add(double seconds) {
    const double bin = std::max(0.0, seconds) / kBinSeconds;
    counts_[static_cast<size_t>(std::min(bin, static_cast<double>(kBins - 1)))] += 1;
    ++total_;
    max_ = std::max(max_, seconds);
  }
  long count() const { return total_; }
  double max() const { return max_; }
  // The upper edge of the bin holding the p-th percentile (s); 0 when empty.
  double percentile(double p) const {
    if (total_ == 0) return 0.0;
    const double rank = p / 100.0 * static_cast<double>(total_);
    int64_t seen = 0;
    for (size_t i = 0; i < kBins; ++i) {
      seen += counts_[i];
      if (static_cast<double>(seen) >= rank) return (i + 1) * kBinSeconds;
    }
    return kBins * kBinSeconds;
  }

 private:
  static constexpr double kBinSeconds = 1e-4;
  static constexpr size_t kBins = 100000;  // 10 s
  std::array<int64_t, kBins> counts_{};
  long total_ = 0;
  double max_ = 0.0;
};

}  // namespace ekf_slam
