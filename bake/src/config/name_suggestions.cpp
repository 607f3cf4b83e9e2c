#include "config/name_suggestions.h"

#include <algorithm>
#include <cctype>
#include <utility>

namespace drape::bake::detail {
namespace {

std::string Lowercase(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// The longest prefix every candidate starts with, lowercased; empty for fewer than two.
std::string SharedPrefix(const std::vector<std::string>& lowered) {
  if (lowered.size() < 2) return {};
  std::string prefix = lowered.front();
  for (const std::string& s : lowered) {
    size_t n = 0;
    while (n < prefix.size() && n < s.size() && prefix[n] == s[n]) ++n;
    prefix.resize(n);
  }
  return prefix;
}

std::string WithoutPrefix(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0 ? s.substr(prefix.size()) : s;
}

}  // namespace

size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

std::vector<std::string> NearestNames(const std::string& name,
                                      const std::vector<std::string>& candidates,
                                      size_t max_count) {
  std::vector<std::string> lowered;
  lowered.reserve(candidates.size());
  for (const std::string& c : candidates) lowered.push_back(Lowercase(c));
  const std::string prefix = SharedPrefix(lowered);
  const std::string query = Lowercase(name);
  const std::string short_query = WithoutPrefix(query, prefix);
  const size_t limit = std::max<size_t>(2, short_query.size() / 3);
  std::vector<std::pair<size_t, size_t>> near;  // (distance, candidate index)
  for (size_t i = 0; i < candidates.size(); ++i) {
    const size_t distance = std::min(EditDistance(query, lowered[i]),
                                     EditDistance(short_query, WithoutPrefix(lowered[i], prefix)));
    if (distance <= limit) near.emplace_back(distance, i);
  }
  std::stable_sort(near.begin(), near.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<std::string> out;
  for (size_t k = 0; k < near.size() && out.size() < max_count; ++k)
    out.push_back(candidates[near[k].second]);
  return out;
}

}  // namespace drape::bake::detail
