#pragma once
// A reactor that ends its call at once with a status (unauthenticated, over a limit, a feature
// that is off), for any callback-API reactor type.
#include <grpcpp/grpcpp.h>

namespace posefuse::server {

template <class Reactor>
class RefusedCall : public Reactor {
 public:
  explicit RefusedCall(grpc::Status status) { this->Finish(std::move(status)); }
  void OnDone() override { delete this; }
};

}  // namespace posefuse::server
