#include "file_tree.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>

#include "seeds.hpp"

namespace posefuse::fuzz {

namespace {

constexpr int kMaxDepth = 4;

bool name_character(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '.' || c == '-';
}

// PATH with unsafe characters dropped and empty, "." and ".." components left out.
std::string safe_path(const std::string& text) {
  std::string out, component;
  int depth = 0;
  auto flush = [&] {
    if (!component.empty() && component != "." && component != ".." && depth < kMaxDepth) {
      if (!out.empty()) out += '/';
      out += component;
      ++depth;
    }
    component.clear();
  };
  for (const char c : text) {
    if (c == '/') flush();
    else if (name_character(c)) component += c;
  }
  flush();
  return out;
}

// True when no folder on the way from `directory` to `relative`'s last component is a link or
// something else than a folder, so that making the entry cannot leave the tree.
bool parents_are_folders(const std::filesystem::path& directory, const std::filesystem::path& relative) {
  std::filesystem::path at = directory;
  for (const auto& component : relative.parent_path()) {
    at /= component;
    std::error_code error;
    const auto status = std::filesystem::symlink_status(at, error);
    if (std::filesystem::exists(status) && !std::filesystem::is_directory(status)) return false;
  }
  return true;
}

}  // namespace

std::vector<TreeEntry> tree_entries(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  std::vector<TreeEntry> entries;
  std::size_t at = bytes.find('\0');
  while (at != std::string::npos && at + 1 < bytes.size()) {
    const std::size_t end = bytes.find('\0', at + 1);
    const std::string entry = bytes.substr(at + 1, end == std::string::npos ? std::string::npos : end - at - 1);
    at = end;
    if (entry.empty()) continue;
    const std::size_t newline = entry.find('\n', 1);
    TreeEntry e;
    e.kind = entry[0];
    e.path = safe_path(entry.substr(1, newline == std::string::npos ? std::string::npos : newline - 1));
    if (newline != std::string::npos) e.content = entry.substr(newline + 1);
    if (!e.path.empty()) entries.push_back(std::move(e));
  }
  return entries;
}

std::string tree_bytes(const std::vector<TreeEntry>& entries) {
  std::string out;
  for (const TreeEntry& e : entries) {
    out += '\0';
    out += e.kind;
    out += e.path + '\n' + e.content;
  }
  return out;
}

std::vector<TreeEntry> entries_of_directory(const std::filesystem::path& root) {
  std::vector<TreeEntry> entries;
  for (const auto& item : std::filesystem::recursive_directory_iterator(root)) {
    const std::string path = std::filesystem::relative(item.path(), root).string();
    if (item.is_directory()) {
      entries.push_back({'d', path, ""});
    } else if (item.is_regular_file()) {
      std::ifstream in(item.path(), std::ios::binary);
      entries.push_back({'f', path, std::string(std::istreambuf_iterator<char>(in), {})});
    }
  }
  return entries;
}

ScratchTree::ScratchTree() {
  // Memory (/dev/shm) unless TMPDIR says otherwise: making and removing a tree for each input on
  // a disk is ten times slower.
  const char* tmp = std::getenv("TMPDIR");
  std::string base = tmp != nullptr && *tmp != '\0' ? tmp : "/tmp";
  if ((tmp == nullptr || *tmp == '\0') && std::filesystem::is_directory("/dev/shm")) base = "/dev/shm";
  std::string pattern = base + "/posefuse-fuzz-XXXXXX";
  if (::mkdtemp(pattern.data()) == nullptr) invariant_failed("mkdtemp failed");
  root_ = pattern;
}

ScratchTree::~ScratchTree() {
  std::error_code ignored;
  std::filesystem::remove_all(root_, ignored);
}

void ScratchTree::make(const std::filesystem::path& directory, const std::vector<TreeEntry>& entries) const {
  std::filesystem::create_directories(directory);
  for (const TreeEntry& e : entries) {
    const std::filesystem::path path = directory / e.path;
    if (!parents_are_folders(directory, e.path)) continue;
    std::error_code error;
    std::filesystem::create_directories(path.parent_path(), error);
    if (error) continue;
    if (e.kind == 'l') {
      (void)::symlink(e.content.c_str(), path.c_str());
    } else if (e.kind == 'p') {
      (void)::mkfifo(path.c_str(), 0600);
    } else if (e.kind == 'd') {
      std::filesystem::create_directories(path, error);
    } else {
      const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC, 0600);
      if (fd < 0) continue;
      std::size_t done = 0;
      while (done < e.content.size()) {
        const ssize_t wrote = ::write(fd, e.content.data() + done, e.content.size() - done);
        if (wrote <= 0) break;
        done += static_cast<std::size_t>(wrote);
      }
      ::close(fd);
    }
  }
}

}  // namespace posefuse::fuzz
