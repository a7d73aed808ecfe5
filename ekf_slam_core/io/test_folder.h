// A gtest fixture with a fresh folder under /tmp (dir_), removed after
// the test, and its listing: for the tests of the file writers.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <string>

namespace ekf_slam {

class TestFolder : public ::testing::Test {
 protected:
  void SetUp() override {
    char pattern[] = "/tmp/ekf_slam_io_test_XXXXXX";
    ASSERT_NE(::mkdtemp(pattern), nullptr);
    dir_ = pattern;
  }
  void TearDown() override { std::system(("rm -rf " + dir_).c_str()); }

  // The names in the folder, one per line, sorted.
  std::string listing() const {
    std::string names;
    FILE* ls = ::popen(("ls -A " + dir_).c_str(), "r");
    char line[512];
    while (ls && std::fgets(line, sizeof line, ls)) names += line;
    if (ls) ::pclose(ls);
    return names;
  }

  std::string dir_;
};

}  // namespace ekf_slam
