#include "session/unknown_options.hpp"

#include <algorithm>
#include <set>
#include <string_view>

namespace posefuse::session {

namespace {

std::string_view prefix_of(std::string_view key) { return key.substr(0, key.find('.')); }

// Insertions, deletions and substitutions that turn a into b.
std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

// A typo changes a few letters; a different word changes most. Near: at most a third of the key.
std::string closest_key(std::string_view key, const std::vector<const OptionTable*>& tables) {
  std::string best;
  std::size_t best_distance = key.size() / 3 + 1;
  for (const OptionTable* table : tables) {
    for (const OptionSpec& spec : *table) {
      const std::size_t distance = edit_distance(key, spec.key);
      if (distance < best_distance) {
        best_distance = distance;
        best = spec.key;
      }
    }
  }
  return best;
}

}  // namespace

std::vector<UnknownOption> unknown_stage_options(const v1::SessionHeader& header,
                                                 const std::vector<const OptionTable*>& tables) {
  std::set<std::string_view> prefixes;
  for (const OptionTable* table : tables)
    for (const OptionSpec& spec : *table) prefixes.insert(prefix_of(spec.key));
  std::set<std::string> keys;  // sorted: the header's map has no order
  for (const auto& [key, value] : header.options()) keys.insert(key);
  std::vector<UnknownOption> unknown;
  for (const std::string& key : keys) {
    if (key.find('.') == std::string::npos || !prefixes.contains(prefix_of(key))) continue;
    const bool declared = std::any_of(tables.begin(), tables.end(),
                                      [&](const OptionTable* table) { return find_option(*table, key) != nullptr; });
    if (!declared) unknown.push_back({key, closest_key(key, tables)});
  }
  return unknown;
}

}  // namespace posefuse::session
