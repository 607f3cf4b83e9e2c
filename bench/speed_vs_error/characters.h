#pragma once
// The characters drape-speed-vs-error measures: the built-in mannequin and the shared characters
// present, each imported at a scale where a human's millimetres compare with another's.

#include <string>
#include <vector>

#include "drape/bake/importer.h"
#include "drape/formats/types.h"

namespace drape::bench {

struct CharacterSpec {
  std::string label;
  std::string path;
  bool human = false;
};

// "builtin": the mannequin; "all": the mannequin and every shared character present (the absent
// ones named on stdout); anything else a path, its stem the label. Fails on a missing path.
std::vector<CharacterSpec> ResolveCharacters(const std::vector<std::string>& requested);

// The extent of `body` along +Y (metres).
float HeightOf(const std::vector<Float3>& body);

// Above this a human is taken to be at the wrong scale (metres).
inline constexpr float kTallestHuman = 2.5f;

// Imports at the detected scale; a human whose skinned rest pose is taller than kTallestHuman
// (Animated_Human's spans 5.26 m: its FBX carries no usable unit; RobotExpressive's glTF
// 4.46 m) is imported again rescaled to 1.75 m, and *note says so. The height is the rest
// pose's, which every measurement uses, not the bind-pose mesh's (8 and 2.6 cm on those two);
// --check holds every human's measured body to kTallestHuman.
bake::ImportOptions ImportFor(const CharacterSpec& spec, bake::Character* character,
                              std::string* note);

}  // namespace drape::bench
