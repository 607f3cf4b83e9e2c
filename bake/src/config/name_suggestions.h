#pragma once
// "Did you mean": the names nearest to a name that was not found (an unknown config key, a joint
// or clip a scene names), by edit distance with case ignored and with the prefix that every
// candidate shares (`mixamorig:`, `B_`) set aside, so that "spine" finds "mixamorig:Spine".

#include <cstddef>
#include <string>
#include <vector>

namespace drape::bake::detail {

// Levenshtein distance between a and b, byte-wise.
size_t EditDistance(const std::string& a, const std::string& b);

// Up to max_count candidates within max(2, a third of the name's length) edits of `name`,
// nearest first (ties in candidate order); empty when none is that near.
std::vector<std::string> NearestNames(const std::string& name,
                                      const std::vector<std::string>& candidates, size_t max_count);

}  // namespace drape::bake::detail
