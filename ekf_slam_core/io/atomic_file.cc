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

std::string writeTarget(const std::string& path) {
  std::string current = path;
  for (int hop = 0; hop < 40; ++hop) {  // more: a loop, which the write then reports
    struct stat status;
    if (::lstat(current.c_str(), &status) != 0 || !S_ISLNK(status.st_mode)) return current;
    std::string link(4096, '\0');
    const ssize_t n = ::readlink(current.c_str(), link.data(), link.size());
    if (n <= 0) return current;
    link.resize(static_cast<size_t>(n));
    if (link.front() != '/') {
      const size_t slash = current.find_last_of('/');
      if (slash != std::string::npos) link = current.substr(0, slash + 1) + link;
    }
    current = link;
  }
  return current;
}

namespace {

const char* kindOf(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
  if (S_ISFIFO(mode)) return "a pipe";
  if (S_ISSOCK(mode)) return "a socket";
  return "a special file";
}

}  // namespace

std::string writeTargetProblem(const std::string& path) {
  struct stat status;
  if (::stat(writeTarget(path).c_str(), &status) != 0 || S_ISREG(status.st_mode)) return "";
  return path + ": is " + kindOf(status.st_mode) + ", not a regular file";
}

std::string temporaryPattern(const std::string& path) { return path + ".saving-XXXXXX"; }

std::string writeTemporary(const std::string& path, const std::string& bytes, std::string* temp) {
  *temp = temporaryPattern(path);
  const int fd = ::mkstemp(temp->data());
  if (fd < 0) {
    temp->clear();
    return path + ": cannot create a temporary file beside it: " + std::strerror(errno);
  }
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
  if (!error.empty()) {
    ::unlink(temp->c_str());
    temp->clear();
  }
  return error;
}

std::string writeFileAtomically(const std::string& path_given, const std::string& bytes) {
  const std::string problem = writeTargetProblem(path_given);
  if (!problem.empty()) return problem + " (nothing written)";
  const std::string path = writeTarget(path_given);
  std::string temp;
  const std::string error = writeTemporary(path, bytes, &temp);
  if (!error.empty()) return error;
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    const std::string why = path + ": cannot replace it: " + std::strerror(errno);
    ::unlink(temp.c_str());
    return why;
  }
  return "";
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
