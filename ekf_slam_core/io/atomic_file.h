// Replacing a file so that a failure never leaves it half written.
#pragma once

#include <string>

namespace ekf_slam {

// Writes `bytes` to a temporary file beside `path` (same filesystem, so the
// rename is atomic), flushes it to the disk (fsync) and renames it over
// `path`, mode 0644. An earlier file at `path` survives any failure (a full
// disk, a crash) unchanged, and no temporary file is left behind. A symlink
// is written through: its target is replaced, the link stays. A path that
// is not a regular file (writeTargetProblem) is refused before anything is
// written. Returns an empty string on success, else the problem with the
// path.
std::string writeFileAtomically(const std::string& path, const std::string& bytes);

// Empty when `path` (or the end of the symlinks it starts) is a regular
// file or does not exist yet, else "<path>: is a directory, not a regular
// file" (a device, a pipe, a socket): what writeFileAtomically refuses,
// for a caller that writes several files to check them all first.
std::string writeTargetProblem(const std::string& path);

// The file a write to `path` lands in: `path`, or the end of the chain of
// symlinks it starts (a dangling one included: the write creates its target).
std::string writeTarget(const std::string& path);

// `bytes` in a new temporary file beside `path` (<path>.saving-XXXXXX, see
// temporaryPattern), mode 0644, flushed to the disk; its name in `temp`.
// On failure nothing is left, `temp` is empty and the problem is returned.
std::string writeTemporary(const std::string& path, const std::string& bytes, std::string* temp);

// The name pattern of those temporaries: <path>.saving-XXXXXX.
std::string temporaryPattern(const std::string& path);

// The whole file; false when it cannot be opened or read.
bool readWholeFile(const std::string& path, std::string* bytes);

}  // namespace ekf_slam
