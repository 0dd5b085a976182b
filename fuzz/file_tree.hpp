#pragma once
// A small tree of files made from fuzz input bytes, for the harnesses of readers that take a
// directory (result reader, directory reader).
//
// The input is a sequence of entries, each starting with a NUL byte:
//   '\0' KIND PATH '\n' CONTENT
// KIND 'f' a regular file holding CONTENT, 'l' a symbolic link to CONTENT (any target text),
// 'p' a FIFO, 'd' a directory; another byte makes a regular file. PATH is relative to the
// tree's root; its components keep only [A-Za-z0-9_.-] and never "." or "..", at most four deep,
// so that an entry is always created inside the tree (a link may point anywhere, which is what
// the readers must refuse to follow). An entry that cannot be made (its parent is a file) is
// left out. Bytes before the first NUL are ignored.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace posefuse::fuzz {

struct TreeEntry {
  char kind = 'f';
  std::string path;
  std::string content;
};

std::vector<TreeEntry> tree_entries(const std::uint8_t* data, std::size_t size);
// The input bytes that tree_entries() reads back as `entries` (for seeds).
std::string tree_bytes(const std::vector<TreeEntry>& entries);
// Entries for every file and directory under `root` (regular files only), for seeds written by
// a real writer.
std::vector<TreeEntry> entries_of_directory(const std::filesystem::path& root);

// A fresh directory under $TMPDIR (default /dev/shm, else /tmp) that removes itself with its content.
class ScratchTree {
 public:
  ScratchTree();
  ~ScratchTree();
  ScratchTree(const ScratchTree&) = delete;
  ScratchTree& operator=(const ScratchTree&) = delete;
  const std::filesystem::path& root() const { return root_; }
  // Makes `entries` beneath `directory` (created; inside root()).
  void make(const std::filesystem::path& directory, const std::vector<TreeEntry>& entries) const;

 private:
  std::filesystem::path root_;
};

}  // namespace posefuse::fuzz
