#pragma once
// A session is a stream of SessionChunk (proto/posefuse/v1/session.proto). Readers and writers
// of its on-disk forms share these two interfaces so that converters and the validator can be
// written once.
#include "posefuse/v1/session.pb.h"

namespace posefuse::session {

using posefuse::v1::SessionChunk;

class ChunkSource {
 public:
  virtual ~ChunkSource() = default;
  // Fills `chunk` with the next chunk and returns true, or returns false at the end.
  // Throws posefuse::Error on unreadable input.
  virtual bool next(SessionChunk& chunk) = 0;
};

class ChunkSink {
 public:
  virtual ~ChunkSink() = default;
  virtual void write(const SessionChunk& chunk) = 0;
  // Flushes and closes; throws posefuse::Error when data could not be written.
  virtual void finish() = 0;
};

}  // namespace posefuse::session
