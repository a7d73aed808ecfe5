#include "ekf_slam_core/io/atomic_file.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

namespace ekf_slam {

std::string writeFileAtomically(const std::string& path, const std::string& bytes) {
  std::string temp = path + ".XXXXXX";
  const int fd = ::mkstemp(temp.data());
  if (fd < 0) return path + ": cannot create a temporary file beside it: " + std::strerror(errno);
  std::string error;
  size_t done = 0;
  while (done < bytes.size() && error.empty()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      error = path + ": write error (" + std::string(n < 0 ? std::strerror(errno) : "no space") +
              "); the earlier file is unchanged";
    } else {
      done += static_cast<size_t>(n);
    }
  }
  if (error.empty() && ::fchmod(fd, 0644) != 0) {
    error = path + ": cannot set the file mode: " + std::strerror(errno);
  }
  if (error.empty() && ::fsync(fd) != 0) {
    error = path + ": cannot flush to the disk (" + std::strerror(errno) +
            "); the earlier file is unchanged";
  }
  if (::close(fd) != 0 && error.empty()) error = path + ": close failed: " + std::strerror(errno);
  if (error.empty() && std::rename(temp.c_str(), path.c_str()) != 0) {
    error = path + ": cannot replace it: " + std::strerror(errno);
  }
  if (!error.empty()) ::unlink(temp.c_str());
  return error;
}

bool readWholeFile(const std::string& path, std::string* bytes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) return false;
  *bytes = buffer.str();
  return true;
}

}  // namespace ekf_slam
