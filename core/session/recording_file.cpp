#include "session/recording_file.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <linux/openat2.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "common/error.hpp"

namespace posefuse::session {

namespace {

constexpr int kReadFlags = O_RDONLY | O_CLOEXEC | O_NONBLOCK;

[[noreturn]] void throw_open_error(int error, const std::string& name) {
  if (error == ENOENT || error == ENOTDIR) throw Error(ErrorCode::kNotFound, name, "does not exist");
  if (error == ELOOP || error == EXDEV) {
    throw_invalid(name,
                  "is or passes through a symbolic link, or leads outside the recording; "
                  "the files of a recording must be regular files inside it");
  }
  throw Error(ErrorCode::kNotFound, name, std::string("cannot be opened: ") + std::strerror(error));
}

// openat2 confined to `directory`; -1 with errno ENOSYS where the kernel (or a seccomp filter)
// does not offer it.
int open_with_openat2(int directory, const std::string& relative) {
  struct open_how how {};
  how.flags = static_cast<std::uint64_t>(kReadFlags | O_NOFOLLOW);
  how.resolve = RESOLVE_BENEATH | RESOLVE_NO_SYMLINKS;
  int fd = -1;
  do {
    fd = static_cast<int>(::syscall(SYS_openat2, directory, relative.c_str(), &how, sizeof how));
  } while (fd < 0 && errno == EINTR);
  return fd;
}

// "a/b.csv": names separated by single slashes, none of them empty, "." or "..".
std::vector<std::string> plain_components(const std::string& relative, const std::string& name) {
  std::vector<std::string> components;
  std::size_t begin = 0;
  while (true) {
    const std::size_t slash = relative.find('/', begin);
    components.push_back(relative.substr(begin, slash - begin));
    const std::string& component = components.back();
    if (component.empty() || component == "." || component == "..") {
      throw_invalid(name, "is not a plain relative name inside the recording");
    }
    if (slash == std::string::npos) return components;
    begin = slash + 1;
  }
}

// The same confinement by hand: one component at a time, none of them a link.
int open_by_components(int directory, const std::vector<std::string>& components) {
  UniqueFd current;
  int at = directory;
  for (std::size_t i = 0; i < components.size(); ++i) {
    const std::string& component = components[i];
    const bool last = i + 1 == components.size();
    const int fd = ::openat(at, component.c_str(), kReadFlags | O_NOFOLLOW | (last ? 0 : O_DIRECTORY));
    if (fd < 0) return -1;
    if (last) return fd;
    current = UniqueFd(fd);
    at = current.get();
  }
  return -1;  // not reached: plain_components returns at least one name
}

}  // namespace

UniqueFd::~UniqueFd() {
  if (fd_ >= 0) ::close(fd_);
}

UniqueFd& UniqueFd::operator=(UniqueFd&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = other.fd_;
    other.fd_ = -1;
  }
  return *this;
}

UniqueFd open_path(const std::filesystem::path& path, const std::string& name) {
  const int fd = ::open(path.c_str(), kReadFlags);
  if (fd < 0) {
    const int error = errno;
    throw Error(ErrorCode::kNotFound, name, "cannot open " + path.string() + ": " + std::strerror(error));
  }
  return UniqueFd(fd);
}

UniqueFd open_beneath(int directory, const std::string& relative, const std::string& name) {
  const std::vector<std::string> components = plain_components(relative, name);
  int fd = open_with_openat2(directory, relative);
  if (fd < 0 && (errno == ENOSYS || errno == EPERM)) fd = open_by_components(directory, components);
  if (fd < 0) throw_open_error(errno, name);
  return UniqueFd(fd);
}

FileKind file_kind(int fd) {
  struct stat status {};
  if (::fstat(fd, &status) != 0) return FileKind::kMissing;
  if (S_ISREG(status.st_mode)) return FileKind::kRegular;
  if (S_ISDIR(status.st_mode)) return FileKind::kDirectory;
  return FileKind::kOther;
}

FileKind entry_kind(int directory, const std::string& entry) {
  struct stat status {};
  if (::fstatat(directory, entry.c_str(), &status, AT_SYMLINK_NOFOLLOW) != 0) {
    return FileKind::kMissing;
  }
  if (S_ISREG(status.st_mode)) return FileKind::kRegular;
  if (S_ISDIR(status.st_mode)) return FileKind::kDirectory;
  return FileKind::kOther;
}

void require_regular_file(int fd, const std::string& name) {
  if (file_kind(fd) != FileKind::kRegular) {
    throw_invalid(name, "is not a regular file (links, FIFOs, devices and sockets are refused)");
  }
}

void require_directory(int fd, const std::string& name) {
  if (file_kind(fd) != FileKind::kDirectory) throw_invalid(name, "is not a directory");
}

std::unique_ptr<std::istream> open_stream_beneath(int directory, const std::string& relative) {
  UniqueFd file = open_beneath(directory, relative, relative);
  require_regular_file(file.get(), relative);
  return std::make_unique<FdInputStream>(std::move(file));
}

bool has_entry(int directory, const std::string& entry, FileKind kind) {
  const FileKind found = entry_kind(directory, entry);
  if (found == FileKind::kMissing) return false;
  if (found != kind) {
    throw_invalid(entry, kind == FileKind::kDirectory ? "is not a directory (links are refused)"
                                                      : "is not a regular file (links, FIFOs and devices are refused)");
  }
  return true;
}

std::vector<std::string> list_directory(int directory, const std::string& name) {
  // fdopendir takes over the descriptor it is given: a duplicate, so `directory` stays open.
  const int copy = ::dup(directory);
  DIR* listing = copy >= 0 ? ::fdopendir(copy) : nullptr;
  if (!listing) {
    if (copy >= 0) ::close(copy);
    throw Error(ErrorCode::kDataLoss, name, "cannot list the directory");
  }
  ::rewinddir(listing);
  std::vector<std::string> names;
  while (const dirent* entry = ::readdir(listing)) {
    const std::string entry_name = entry->d_name;
    if (entry_name != "." && entry_name != "..") names.push_back(entry_name);
  }
  ::closedir(listing);
  return names;
}

std::string read_all(int fd, const std::string& name, std::uint64_t max_bytes) {
  struct stat status {};
  if (::fstat(fd, &status) != 0) throw Error(ErrorCode::kDataLoss, name, "cannot stat the file");
  const auto size = static_cast<std::uint64_t>(status.st_size);
  if (size > max_bytes) {
    throw Error(ErrorCode::kResourceExhausted, name,
                "is " + std::to_string(size) + " bytes, at most " + std::to_string(max_bytes) + " allowed");
  }
  std::string bytes(static_cast<std::size_t>(size), '\0');
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t got = ::pread(fd, bytes.data() + done, bytes.size() - done, static_cast<off_t>(done));
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) throw Error(ErrorCode::kDataLoss, name, "read fewer bytes than the file size");
    done += static_cast<std::size_t>(got);
  }
  return bytes;
}

FdInputStream::FdInputStream(UniqueFd fd) : std::istream(nullptr), buffer_(std::move(fd)) {
  rdbuf(&buffer_);  // also clears the badbit that the null buffer set
}

FdInputStream::Buffer::int_type FdInputStream::Buffer::underflow() {
  if (gptr() < egptr()) return traits_type::to_int_type(*gptr());
  ssize_t got = -1;
  do {
    got = ::read(fd_.get(), data_, sizeof data_);
  } while (got < 0 && errno == EINTR);
  // std::istream turns an exception from its buffer into badbit.
  if (got < 0) throw std::ios_base::failure("read failed");
  if (got == 0) return traits_type::eof();
  setg(data_, data_, data_ + got);
  return traits_type::to_int_type(data_[0]);
}

FdInputStream::Buffer::pos_type FdInputStream::Buffer::seekoff(off_type offset, std::ios_base::seekdir dir,
                                                               std::ios_base::openmode) {
  int whence = SEEK_SET;
  if (dir == std::ios_base::cur) {
    whence = SEEK_CUR;
    offset -= egptr() - gptr();  // the file is ahead of the reader by what is buffered
  } else if (dir == std::ios_base::end) {
    whence = SEEK_END;
  }
  const off_t at = ::lseek(fd_.get(), static_cast<off_t>(offset), whence);
  setg(data_, data_, data_);
  return at < 0 ? pos_type(off_type(-1)) : pos_type(static_cast<off_type>(at));
}

FdInputStream::Buffer::pos_type FdInputStream::Buffer::seekpos(pos_type position, std::ios_base::openmode which) {
  return seekoff(off_type(position), std::ios_base::beg, which);
}

}  // namespace posefuse::session
