// Saves that refuse what is not a file, and write through symlinks.
#include "ekf_slam_core/io/atomic_file.h"
#include "ekf_slam_core/io/test_folder.h"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdlib>
#include <string>

namespace ekf_slam {
namespace {

using AtomicFile = TestFolder;

TEST_F(AtomicFile, ReplacesARegularFile) {
  const std::string path = dir_ + "/map.yaml";
  ASSERT_EQ(writeFileAtomically(path, "old"), "");
  ASSERT_EQ(writeFileAtomically(path, "new"), "");
  std::string bytes;
  ASSERT_TRUE(readWholeFile(path, &bytes));
  EXPECT_EQ(bytes, "new");
  EXPECT_EQ(listing(), "map.yaml\n");  // no temporary left
}

// A device, a pipe, a directory or a socket at the path is refused with a
// message naming it, and nothing is written: no temporary beside it, the
// pipe not opened (a reader would block), the device untouched.
TEST_F(AtomicFile, RefusesWhatIsNotAFileWithNothingWritten) {
  const std::string fifo = dir_ + "/pipe";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  const std::string folder = dir_ + "/folder";
  ASSERT_EQ(::mkdir(folder.c_str(), 0755), 0);
  const std::string socket_path = dir_ + "/socket";
  const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
  ASSERT_GE(fd, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  socket_path.copy(address.sun_path, sizeof(address.sun_path) - 1);
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)), 0);
  const std::string before = listing();

  for (const auto& [path, kind] :
       {std::make_pair(fifo, "a pipe"), std::make_pair(folder, "a directory"),
        std::make_pair(socket_path, "a socket")}) {
    const std::string error = writeFileAtomically(path, "bytes");
    EXPECT_NE(error.find(path + ": is " + kind), std::string::npos) << error;
    EXPECT_NE(error.find("nothing written"), std::string::npos) << error;
    EXPECT_EQ(writeTargetProblem(path),
              path + ": is " + std::string(kind) + ", not a regular file");
  }
  ::close(fd);
  EXPECT_EQ(listing(), before);
  struct stat status;
  ASSERT_EQ(::stat(folder.c_str(), &status), 0);
  EXPECT_TRUE(S_ISDIR(status.st_mode));

  const std::string device_error = writeFileAtomically("/dev/null", "bytes");
  EXPECT_NE(device_error.find("/dev/null: is a device"), std::string::npos) << device_error;
  ASSERT_EQ(::stat("/dev/null", &status), 0);
  EXPECT_TRUE(S_ISCHR(status.st_mode));
}

// A symlink is written through: the target gets the bytes, the link stays
// a link (also through a chain of relative links, and to a target not made
// yet), and what the link points to as a whole is refused as its target is.
TEST_F(AtomicFile, WritesThroughSymlinks) {
  const std::string target = dir_ + "/maps/office.yaml";
  ASSERT_EQ(::mkdir((dir_ + "/maps").c_str(), 0755), 0);
  ASSERT_EQ(writeFileAtomically(target, "old"), "");
  ASSERT_EQ(::symlink("maps/office.yaml", (dir_ + "/current.yaml").c_str()), 0);
  ASSERT_EQ(::symlink("current.yaml", (dir_ + "/latest.yaml").c_str()), 0);

  ASSERT_EQ(writeFileAtomically(dir_ + "/latest.yaml", "new"), "");
  std::string bytes;
  ASSERT_TRUE(readWholeFile(target, &bytes));
  EXPECT_EQ(bytes, "new");
  struct stat status;
  ASSERT_EQ(::lstat((dir_ + "/latest.yaml").c_str(), &status), 0);
  EXPECT_TRUE(S_ISLNK(status.st_mode));
  ASSERT_EQ(::lstat((dir_ + "/current.yaml").c_str(), &status), 0);
  EXPECT_TRUE(S_ISLNK(status.st_mode));

  ASSERT_EQ(::symlink("maps/new.yaml", (dir_ + "/dangling.yaml").c_str()), 0);
  ASSERT_EQ(writeFileAtomically(dir_ + "/dangling.yaml", "created"), "");
  ASSERT_TRUE(readWholeFile(dir_ + "/maps/new.yaml", &bytes));
  EXPECT_EQ(bytes, "created");

  ASSERT_EQ(::symlink("maps", (dir_ + "/to_folder").c_str()), 0);
  EXPECT_NE(writeFileAtomically(dir_ + "/to_folder", "x").find("is a directory"),
            std::string::npos);
}

}  // namespace
}  // namespace ekf_slam
