#include "server/random_id.hpp"

#include <random>

namespace posefuse::server {

std::string random_hex_id() {
  std::random_device random;
  static const char* const kHex = "0123456789abcdef";
  std::string id;
  for (int i = 0; i < 4; ++i) {
    const unsigned value = random();
    for (int k = 0; k < 8; ++k) id += kHex[(value >> (4 * k)) & 0xF];
  }
  return id;
}

}  // namespace posefuse::server
