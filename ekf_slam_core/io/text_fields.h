// Small text helpers the io readers share (internal to ekf_slam_core/io).
#pragma once

#include <string>

namespace ekf_slam {
namespace io_text {

// `s` without leading and trailing blanks (space, tab, carriage return).
std::string trim(const std::string& s);
// The whole of `text` (blanks around allowed) as a number; false when
// anything else is there. Infinities and NaN are numbers here: each reader
// decides whether it accepts them.
bool parseNumber(const std::string& text, double* value);

}  // namespace io_text
}  // namespace ekf_slam
