// The .npy / .npz reader (body/npz_reader.*) on arbitrary bytes, as an .npy array and as an
// .npz archive: every array read holds as many values as its shape says. An archive member
// may not make the reader allocate far more than the archive's size (-malloc_limit_mb in
// scripts/fuzz.sh): a deflated member claiming gigabytes is a memory bomb.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "../tests/body/npz_writer.hpp"
#include "body/npz_reader.hpp"
#include "common/error.hpp"
#include "seeds.hpp"

using namespace posefuse;

namespace {

void check_array(const body::NpyArray& array) {
  std::size_t count = 1;
  for (const std::int64_t d : array.shape) {
    if (d < 0) fuzz::invariant_failed("negative dimension");
    count *= static_cast<std::size_t>(d);
  }
  if (array.values.size() != count) fuzz::invariant_failed("values do not match the shape");
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::init_harness([] {
    namespace t = body::testing;
    const std::string matrix = t::npy({2, 3}, {1, 2, 3, 4, 5, 6});
    const std::string fortran = t::npy({3, 2}, {1, -2, 3, 4, 5, 6}, "<i4", true);
    const std::string single = t::npy({4}, {0.5, 1.5, -2.5, 3.5}, "<f4");
    return fuzz::Seeds{{"matrix.npy", matrix},
                       {"stored.npz", t::zip({{"a.npy", matrix}, {"b.npy", single}}, false)},
                       {"deflated.npz", t::zip({{"a.npy", fortran}, {"b.npy", single}}, true)},
                       {"zip64.npz", t::zip({{"a.npy", matrix}}, true, true)}};
  });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    check_array(body::parse_npy(bytes, "fuzz.npy"));
  } catch (const Error&) {
  }
  try {
    for (const auto& [name, array] : body::parse_npz(bytes, "fuzz.npz")) check_array(array);
  } catch (const Error&) {
  }
  return 0;
}
