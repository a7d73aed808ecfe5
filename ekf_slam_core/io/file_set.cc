#include "ekf_slam_core/io/file_set.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <sstream>

#include "ekf_slam_core/io/atomic_file.h"

namespace ekf_slam {
namespace {

constexpr const char* kJournalHeader = "ekf_slam file set 1";
constexpr const char* kJournalEnd = "end";

// One file of a committed set: its temporary is renamed over it, or (no
// temporary) it is removed.
struct JournalEntry {
  std::string path;
  std::string temporary;
};

std::string formatJournal(const std::vector<JournalEntry>& entries) {
  std::string text = std::string(kJournalHeader) + "\n";
  for (const JournalEntry& e : entries) text += e.path + "\n" + e.temporary + "\n";
  return text + kJournalEnd + "\n";
}

bool parseJournal(const std::string& text, std::vector<JournalEntry>* entries) {
  std::istringstream in(text);
  std::string line;
  if (!std::getline(in, line) || line != kJournalHeader) return false;
  std::vector<JournalEntry> parsed;
  while (std::getline(in, line)) {
    if (line == kJournalEnd) {
      *entries = std::move(parsed);
      return true;
    }
    JournalEntry entry;
    entry.path = line;
    if (entry.path.empty() || !std::getline(in, entry.temporary)) return false;
    parsed.push_back(std::move(entry));
  }
  return false;  // no end line: not a journal this code wrote
}

// Makes the renames in the directory of `path` durable (best effort: a
// filesystem without directory fsync still has them).
void syncDirectoryOf(const std::string& path) {
  const std::string directory = std::filesystem::path(path).parent_path().string();
  const int fd = ::open(directory.empty() ? "." : directory.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

// Puts a committed set in place: each temporary that still exists renamed
// over its file (one already renamed is gone), each removal done.
std::string applyJournal(const std::vector<JournalEntry>& entries, const FileSetStepHook& step) {
  for (const JournalEntry& e : entries) {
    if (e.temporary.empty()) {
      if (::unlink(e.path.c_str()) != 0 && errno != ENOENT) {
        return e.path + ": cannot remove it: " + std::strerror(errno);
      }
      if (step) step("removal");
      continue;
    }
    if (::access(e.temporary.c_str(), F_OK) == 0 &&
        std::rename(e.temporary.c_str(), e.path.c_str()) != 0) {
      return e.path + ": cannot replace it: " + std::strerror(errno);
    }
    if (step) step("rename");
  }
  if (!entries.empty()) syncDirectoryOf(entries.front().path);
  return "";
}

// Removes <path>.saving-XXXXXX files beside the file a write to `path`
// lands in.
void removeTemporaries(const std::string& path) {
  const std::filesystem::path target(writeTarget(path));
  const std::string pattern = temporaryPattern(target.filename().string());
  const std::string prefix = pattern.substr(0, pattern.size() - 6);
  std::filesystem::path directory = target.parent_path();
  if (directory.empty()) directory = ".";
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(directory, error)) {
    const std::string name = entry.path().filename().string();
    if (name.size() == pattern.size() && name.compare(0, prefix.size(), prefix) == 0) {
      std::filesystem::remove(entry.path(), error);
    }
  }
}

}  // namespace

std::string finishInterruptedSave(const std::string& journal,
                                  const std::vector<std::string>& paths) {
  std::string text;
  if (::access(journal.c_str(), F_OK) == 0) {
    std::vector<JournalEntry> entries;
    if (!readWholeFile(journal, &text) || !parseJournal(text, &entries)) {
      return journal + ": not a save journal of this program (left as it is)";
    }
    const std::string error = applyJournal(entries, nullptr);
    if (!error.empty()) return error + " (completing the save that " + journal + " records)";
    if (::unlink(journal.c_str()) != 0) {
      return journal + ": cannot remove it: " + std::strerror(errno);
    }
    syncDirectoryOf(journal);
  }
  removeTemporaries(journal);
  for (const std::string& path : paths) removeTemporaries(path);
  return "";
}

std::string writeFileSet(const std::string& journal, const std::vector<FileSetEntry>& files,
                         const FileSetStepHook& step) {
  std::vector<std::string> paths;
  for (const FileSetEntry& file : files) {
    if (file.path.find('\n') != std::string::npos || file.path.empty()) {
      return "'" + file.path + "': not a file name (nothing written)";
    }
    const std::string problem = writeTargetProblem(file.path);
    if (!problem.empty()) return problem + " (nothing written)";
    paths.push_back(file.path);
  }
  std::string error = finishInterruptedSave(journal, paths);
  if (!error.empty()) return error;

  std::vector<JournalEntry> entries;
  auto discard = [&entries] {
    for (const JournalEntry& e : entries) {
      if (!e.temporary.empty()) ::unlink(e.temporary.c_str());
    }
  };
  for (const FileSetEntry& file : files) {
    JournalEntry entry;
    entry.path = writeTarget(file.path);
    if (file.bytes) {
      error = writeTemporary(entry.path, *file.bytes, &entry.temporary);
      if (!error.empty()) {
        discard();
        return error + " (nothing written)";
      }
      if (entry.temporary.find('\n') != std::string::npos) {
        ::unlink(entry.temporary.c_str());
        discard();
        return entry.path + ": not a file name (nothing written)";
      }
      if (step) step("temporary");
    }
    entries.push_back(std::move(entry));
  }

  // The commit: from here on the new set is what a reader gets.
  std::string journal_temporary;
  error = writeTemporary(journal, formatJournal(entries), &journal_temporary);
  if (error.empty() && std::rename(journal_temporary.c_str(), journal.c_str()) != 0) {
    error = journal + ": cannot put it in place: " + std::strerror(errno);
    ::unlink(journal_temporary.c_str());
  }
  if (!error.empty()) {
    discard();
    return error + " (nothing written)";
  }
  syncDirectoryOf(journal);
  if (step) step("commit");

  error = applyJournal(entries, step);
  if (!error.empty()) return error + "; the next save or load of " + journal + " completes it";
  if (::unlink(journal.c_str()) != 0) {
    return journal + ": cannot remove it: " + std::strerror(errno);
  }
  if (step) step("journal removed");
  return "";
}

}  // namespace ekf_slam
