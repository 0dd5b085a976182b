#pragma once
// Random identifiers for jobs and spooled uploads: 32 hex digits from std::random_device, so
// that ids cannot be guessed from one another and replicas sharing a store do not collide.
#include <string>

namespace posefuse::server {

std::string random_hex_id();

}  // namespace posefuse::server
