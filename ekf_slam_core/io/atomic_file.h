// Replacing a file so that a failure never leaves it half written.
#pragma once

#include <string>

namespace ekf_slam {

// Writes `bytes` to a temporary file beside `path` (same filesystem, so the
// rename is atomic), flushes it to the disk (fsync) and renames it over
// `path`, mode 0644. An earlier file at `path` survives any failure (a full
// disk, a crash) unchanged, and no temporary file is left behind. Returns
// an empty string on success, else the problem with the path.
std::string writeFileAtomically(const std::string& path, const std::string& bytes);

// The whole file; false when it cannot be opened or read.
bool readWholeFile(const std::string& path, std::string* bytes);

}  // namespace ekf_slam
