// Files saved as one set: a save stopped at any step leaves the earlier set
// or the new one, never a mix, and no temporaries once the next save or a
// load has run.
#include "ekf_slam_core/io/file_set.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "ekf_slam_core/io/atomic_file.h"
#include "ekf_slam_core/io/test_folder.h"

namespace ekf_slam {
namespace {

class FileSet : public TestFolder {
 protected:
  // name → content of the set's files that exist ("" for none: absent).
  std::map<std::string, std::string> contents(const std::vector<std::string>& names) const {
    std::map<std::string, std::string> found;
    for (const std::string& name : names) {
      std::string bytes;
      found[name] = readWholeFile(dir_ + "/" + name, &bytes) ? bytes : "";
    }
    return found;
  }

  // A landmark map with a grid beside it (image and YAML), each file's
  // content tagged with the save's name; without a grid the set removes it.
  std::vector<FileSetEntry> set(const std::string& tag, bool with_grid) const {
    std::vector<FileSetEntry> files;
    if (with_grid) {
      files.push_back({dir_ + "/map_grid.pgm", "image of " + tag});
      files.push_back({dir_ + "/map_grid.yaml", "grid of " + tag});
    } else {
      files.push_back({dir_ + "/map_grid.pgm", std::nullopt});
      files.push_back({dir_ + "/map_grid.yaml", std::nullopt});
    }
    files.push_back({dir_ + "/map.yaml", "landmarks of " + tag});
    return files;
  }

  std::map<std::string, std::string> expected(const std::string& tag, bool with_grid) const {
    return {{"map_grid.pgm", with_grid ? "image of " + tag : ""},
            {"map_grid.yaml", with_grid ? "grid of " + tag : ""},
            {"map.yaml", "landmarks of " + tag}};
  }

  std::string journal() const { return journalFor(dir_ + "/map.yaml"); }
  std::vector<std::string> paths() const {
    return {dir_ + "/map_grid.pgm", dir_ + "/map_grid.yaml", dir_ + "/map.yaml"};
  }
};

const std::vector<std::string> kNames = {"map_grid.pgm", "map_grid.yaml", "map.yaml"};

TEST_F(FileSet, WritesEveryFileAndLeavesNothingElse) {
  ASSERT_EQ(writeFileSet(journal(), set("first", true)), "");
  EXPECT_EQ(contents(kNames), expected("first", true));
  EXPECT_EQ(listing(), "map.yaml\nmap_grid.pgm\nmap_grid.yaml\n");
  // A set without the grid removes the earlier one.
  ASSERT_EQ(writeFileSet(journal(), set("second", false)), "");
  EXPECT_EQ(contents(kNames), expected("second", false));
  EXPECT_EQ(listing(), "map.yaml\n");
}

// The save runs in a child process that ends (as a kill would end it) just
// after step `stop`, for every step of the save: three temporaries, the
// commit, three renames or removals, the journal's removal. Before the
// commit the earlier set is on the disk, untouched; after it, the next load
// (finishInterruptedSave) completes the new set. Either way no temporary
// is left after it.
TEST_F(FileSet, ASaveStoppedAtEachStepLeavesTheEarlierOrTheNewSet) {
  const int kSteps = 8;
  for (int stop = 1; stop <= kSteps + 1; ++stop) {
    for (const bool new_grid : {true, false}) {
      SCOPED_TRACE("stopped after step " + std::to_string(stop) +
                   (new_grid ? ", new set with a grid" : ", new set without a grid"));
      ASSERT_EQ(writeFileSet(journal(), set("old", true)), "");
      int steps = 0;
      const pid_t child = ::fork();
      ASSERT_GE(child, 0);
      if (child == 0) {
        writeFileSet(journal(), set("new", new_grid), [&](const std::string&) {
          if (++steps == stop) ::_exit(0);
        });
        ::_exit(1);  // the save ended before step `stop`
      }
      int status = 0;
      ASSERT_EQ(::waitpid(child, &status, 0), child);
      ASSERT_TRUE(WIFEXITED(status));
      // A save without a grid has no temporaries for it: 6 steps in all.
      const int steps_of_save = new_grid ? kSteps : kSteps - 2;
      ASSERT_EQ(WEXITSTATUS(status), stop <= steps_of_save ? 0 : 1);
      const int temporaries = new_grid ? 3 : 1;
      const bool committed = stop > temporaries;
      if (!committed) {
        // Only temporaries were written: the earlier set is whole as it is.
        EXPECT_EQ(contents(kNames), expected("old", true));
      }
      ASSERT_EQ(finishInterruptedSave(journal(), paths()), "");
      EXPECT_EQ(contents(kNames), committed ? expected("new", new_grid) : expected("old", true));
      EXPECT_EQ(listing(),
                new_grid || !committed ? "map.yaml\nmap_grid.pgm\nmap_grid.yaml\n" : "map.yaml\n");
    }
  }
}

// The next save completes a stopped one first, and leaves no temporary.
TEST_F(FileSet, TheNextSaveRemovesWhatAStoppedSaveLeft) {
  ASSERT_EQ(writeFileSet(journal(), set("old", true)), "");
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    int steps = 0;
    writeFileSet(journal(), set("stopped", true), [&](const std::string&) {
      if (++steps == 2) ::_exit(0);  // two temporaries written, no commit
    });
    ::_exit(1);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  // A temporary of writeFileAtomically's, left by a kill, goes too.
  std::string temporary;
  ASSERT_EQ(writeTemporary(dir_ + "/map.yaml", "half", &temporary), "");
  EXPECT_NE(listing(), "map.yaml\nmap_grid.pgm\nmap_grid.yaml\n");
  ASSERT_EQ(writeFileSet(journal(), set("next", true)), "");
  EXPECT_EQ(contents(kNames), expected("next", true));
  EXPECT_EQ(listing(), "map.yaml\nmap_grid.pgm\nmap_grid.yaml\n");
}

// A path that is a directory, a pipe or a device refuses the whole set
// before any file is written.
TEST_F(FileSet, RefusesTheSetWhenOnePathIsNotAFile) {
  ASSERT_EQ(writeFileSet(journal(), set("old", true)), "");
  const std::string fifo = dir_ + "/pipe";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  for (const std::string& bad : {fifo, dir_, std::string("/dev/null")}) {
    SCOPED_TRACE(bad);
    std::vector<FileSetEntry> files = set("new", true);
    files.insert(files.begin() + 1, FileSetEntry{bad, std::string("x")});
    const std::string error = writeFileSet(journal(), files);
    EXPECT_NE(error.find(bad), std::string::npos) << error;
    EXPECT_NE(error.find("nothing written"), std::string::npos) << error;
    EXPECT_EQ(contents(kNames), expected("old", true));
    EXPECT_EQ(listing(), "map.yaml\nmap_grid.pgm\nmap_grid.yaml\npipe\n");
  }
}

// A symlink in the set is written through: its target gets the content.
TEST_F(FileSet, WritesThroughASymlink) {
  const std::string target = dir_ + "/maps_target.yaml";
  ASSERT_EQ(::symlink("maps_target.yaml", (dir_ + "/map.yaml").c_str()), 0);
  ASSERT_EQ(writeFileSet(journal(), set("linked", true)), "");
  struct stat status;
  ASSERT_EQ(::lstat((dir_ + "/map.yaml").c_str(), &status), 0);
  EXPECT_TRUE(S_ISLNK(status.st_mode));
  std::string bytes;
  ASSERT_TRUE(readWholeFile(target, &bytes));
  EXPECT_EQ(bytes, "landmarks of linked");
}

}  // namespace
}  // namespace ekf_slam
