#pragma once
// --dump-maps: the inputs drape-replay-maps runs alone, written under DIR/replay/ (made on first
// use) as <character>_mix.motions and <character>_<setting>.drape. Fail on any write error.

#include <string>

#include "characters.h"
#include "drape/formats/body_map_data.h"
#include "query_sets.h"
#include "sweep.h"

namespace drape::bench {

// The mix's motions with the step and response every method is timed with.
void DumpMotions(const std::string& out_dir, const CharacterSpec& spec, const QuerySet& mix);

// One rest-pose setting's pose, as an asset holding only its body maps.
void DumpMapPose(const std::string& out_dir, const CharacterSpec& spec, const MapSetting& m,
                 const BodyMapPose& pose);

}  // namespace drape::bench
