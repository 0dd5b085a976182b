// The directory reader (session/directory_reader.*) on a recording directory made from the
// input (file_tree.hpp: files, links to anywhere, FIFOs, folders), next to a folder outside the
// recording that holds a secret CSV, a PNG and a FIFO. Every chunk is read until the end or the
// first posefuse::Error. Beyond no crash: a FIFO never hangs the reader (-timeout), nothing
// outside the recording is opened (inotify on the outside folder), and the secret never
// reaches an error message (reads stay beneath the recording, docs/recording-format.md). Errors
// quote the recording's own names and fields, so an input that itself holds the secret (the
// fuzzer learns it from the comparison below) is judged by the inotify check alone.
#include <sys/inotify.h>
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <string_view>

#include "common/error.hpp"
#include "file_tree.hpp"
#include "seeds.hpp"
#include "session/directory_reader.hpp"
#include "session/directory_writer.hpp"

using namespace posefuse;

namespace {

constexpr const char* kSecret = "5ecret0utside";

bool holds_secret(std::string_view text) { return text.find(kSecret) != std::string_view::npos; }

// A scratch tree with the outside folder made once and watched for opens.
struct Scratch {
  fuzz::ScratchTree tree;
  int watch = -1;
  Scratch() {
    tree.make(tree.root() / "outside",
              {{'f', "secret.csv", std::string("t_us,gx,gy,gz,ax,ay,az,mx,my,mz\n1,2,3,4,5,6,7,8,9,0\n# ") + kSecret},
               {'f', "secret.png", fuzz::encoded_image(4, 3, CV_16UC1, ".png")},
               {'p', "fifo", ""}});
    watch = ::inotify_init1(IN_NONBLOCK | IN_CLOEXEC);
    if (watch < 0 || ::inotify_add_watch(watch, (tree.root() / "outside").c_str(), IN_OPEN | IN_ACCESS) < 0) {
      fuzz::invariant_failed("inotify on the outside folder");
    }
  }
  // True when something opened or read a file of the outside folder since the last call.
  bool outside_touched() const {
    alignas(inotify_event) char events[4096];
    return ::read(watch, events, sizeof events) > 0;
  }
};

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::init_harness([] {
    fuzz::ScratchTree scratch;
    {
      session::DirectoryWriter writer(scratch.root() / "recording");
      for (const v1::SessionChunk& chunk : fuzz::tiny_session()) writer.write(chunk);
      writer.finish();
    }
    std::vector<fuzz::TreeEntry> recording = fuzz::entries_of_directory(scratch.root() / "recording");
    fuzz::Seeds seeds{{"recording", fuzz::tree_bytes(recording)}};
    // The same recording with files replaced by links out of it and by FIFOs.
    for (fuzz::TreeEntry& e : recording) {
      if (e.path.rfind("depth/", 0) == 0) e = {'l', e.path, "../../outside/secret.png"};
      else if (e.path.rfind("imu/", 0) == 0) e = {'p', e.path, ""};
      else if (e.path == "audio.wav") e = {'l', e.path, "../outside/fifo"};
    }
    recording.push_back({'l', "imu/outside.csv", "../../outside/secret.csv"});
    seeds.push_back({"links-and-fifos", fuzz::tree_bytes(recording)});
    return seeds;
  });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const Scratch scratch;
  const auto recording = scratch.tree.root() / "recording";
  const std::vector<fuzz::TreeEntry> entries = fuzz::tree_entries(data, size);
  scratch.tree.make(recording, entries);
  try {
    session::DirectoryReader reader(recording);
    session::SessionChunk chunk;
    while (reader.next(chunk)) {
    }
  } catch (const Error& error) {
    if (holds_secret(error.what()) && std::none_of(entries.begin(), entries.end(), [](const fuzz::TreeEntry& e) {
          return holds_secret(e.path) || holds_secret(e.content);
        })) {
      fuzz::invariant_failed("secret in an error");
    }
  }
  if (scratch.outside_touched()) fuzz::invariant_failed("a file outside the recording was opened");
  std::filesystem::remove_all(recording);
  return 0;
}
