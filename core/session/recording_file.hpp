#pragma once
// Opening the files of a recording so that reading can neither leave it nor hang.
//
// A recording is untrusted input: a directory may hold a symbolic link to a file elsewhere, a
// name with "..", or a FIFO that blocks every read. Inside a recording every file is opened
// relative to an open directory, beneath it, without following any link (openat2 with
// RESOLVE_BENEATH | RESOLVE_NO_SYMLINKS, or O_NOFOLLOW component by component where the kernel
// has no openat2), without blocking (O_NONBLOCK: opening a FIFO returns at once), and only a
// regular file is read (fstat). Error messages name the file, never its content.
#include <cstdint>
#include <filesystem>
#include <istream>
#include <memory>
#include <streambuf>
#include <string>
#include <vector>

namespace posefuse::session {

// An open file descriptor, closed on destruction.
class UniqueFd {
 public:
  UniqueFd() = default;
  explicit UniqueFd(int fd) : fd_(fd) {}
  ~UniqueFd();
  UniqueFd(UniqueFd&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }
  UniqueFd& operator=(UniqueFd&& other) noexcept;
  UniqueFd(const UniqueFd&) = delete;
  UniqueFd& operator=(const UniqueFd&) = delete;
  int get() const { return fd_; }

 private:
  int fd_ = -1;
};

// What an open file or a directory entry is.
enum class FileKind { kMissing, kRegular, kDirectory, kOther };

// Opens `path` as given by the caller (links in it are followed: the caller chose the path),
// read-only and without blocking. kNotFound (field `name`) when it cannot be opened.
UniqueFd open_path(const std::filesystem::path& path, const std::string& name);

// Opens `relative` (e.g. "imu/left.csv") beneath the open directory `directory`: no component
// may be a symbolic link, "." or "..", and nothing outside `directory` is reached. Read-only,
// without blocking. kNotFound when it does not exist, kInvalidArgument naming `name` for a
// link or a name that would leave the directory.
UniqueFd open_beneath(int directory, const std::string& relative, const std::string& name);

FileKind file_kind(int fd);
// The kind of the entry `entry` (one name, no '/') of `directory`, not following a link (a
// link is kOther).
FileKind entry_kind(int directory, const std::string& entry);
// Throws kInvalidArgument naming `name` unless `fd` is a regular file / a directory.
void require_regular_file(int fd, const std::string& name);
void require_directory(int fd, const std::string& name);

// Whether `directory` has the optional entry `entry` (one name) of `kind` (kRegular or
// kDirectory); anything else under that name (a link, a FIFO, a file where a folder belongs)
// throws kInvalidArgument naming `entry` rather than being silently skipped.
bool has_entry(int directory, const std::string& entry, FileKind kind);
// The regular file `relative` opened beneath `directory` as a stream (open_beneath,
// require_regular_file); errors name `relative`.
std::unique_ptr<std::istream> open_stream_beneath(int directory, const std::string& relative);

// The names in an open directory, without "." and "..", in no particular order.
std::vector<std::string> list_directory(int directory, const std::string& name);

// The whole content of a regular file; kResourceExhausted when it is larger than `max_bytes`,
// kDataLoss when reading fails.
std::string read_all(int fd, const std::string& name, std::uint64_t max_bytes);

// A buffered input stream over a file descriptor it owns. A read error sets badbit.
class FdInputStream : public std::istream {
 public:
  explicit FdInputStream(UniqueFd fd);

 private:
  class Buffer : public std::streambuf {
   public:
    explicit Buffer(UniqueFd fd) : fd_(std::move(fd)) {}

   protected:
    int_type underflow() override;
    pos_type seekoff(off_type offset, std::ios_base::seekdir dir, std::ios_base::openmode which) override;
    pos_type seekpos(pos_type position, std::ios_base::openmode which) override;

   private:
    UniqueFd fd_;
    char data_[1 << 16];
  };
  Buffer buffer_;
};

}  // namespace posefuse::session
