// Several files replaced as one set, so that no reader pairs files of two
// saves (a landmark map with the occupancy grid beside it, a grid's YAML
// with its image).
//
// writeFileSet writes each file to a temporary beside it
// (<file>.saving-XXXXXX, flushed to the disk); then puts in place, as one
// rename, a journal that names every temporary and its file: the commit;
// then renames each temporary over its file, and removes the journal.
// A save that stops before the commit (a kill, a full disk, a power cut)
// leaves the earlier set as it was; one that stops after it is completed
// by finishInterruptedSave, which the next save and every load of the set
// call first. finishInterruptedSave also removes the temporaries a stopped
// save left.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace ekf_slam {

struct FileSetEntry {
  std::string path;
  // The new content; none: the file is removed at the commit (a part the
  // new set does not have, such as a grid that does not exist yet).
  std::optional<std::string> bytes;
};

// For the tests of a save stopped at each step: called after each step
// ("temporary", "commit", "rename", "removal", "journal removed"); a test
// ends the process there.
using FileSetStepHook = std::function<void(const std::string& step)>;

// Writes `files` as one set (paths with a newline are refused), with the
// journal at `journal` (a path beside the set's main file). A path that is
// a symlink is written through; one that is a directory, a device or a pipe
// refuses the whole set before anything is written. Empty on success, else
// the problem, naming the file; the earlier set is then as it was, or
// (after the commit) complete but for finishInterruptedSave.
std::string writeFileSet(const std::string& journal, const std::vector<FileSetEntry>& files,
                         const FileSetStepHook& step = nullptr);

// Completes the save whose journal is `journal`, if one stopped after its
// commit, and removes the temporaries that saves of `paths` left. Empty on
// success (nothing to do included), else the problem.
std::string finishInterruptedSave(const std::string& journal,
                                  const std::vector<std::string>& paths);

// The journal of the set whose main file is `path`: <path>.journal.
inline std::string journalFor(const std::string& path) { return path + ".journal"; }

}  // namespace ekf_slam
