#pragma once
// One run of drape-speed-vs-error: every method and setting of the sweep (sweep.h) and the peers
// on each character's query sets, against the exact mesh, at the rest pose and at a pose of its
// longest clip; the rows, the report's sections and the notes it collects, written by Finish.

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "characters.h"
#include "drape/bake/importer.h"
#include "drape/bake/mesh_reference.h"
#include "drape/bake/regions.h"
#include "drape/formats/character_asset.h"
#include "evaluation.h"
#include "methods.h"
#include "options.h"
#include "query_sets.h"
#include "report.h"

namespace drape::bench {

class Measurement {
 public:
  explicit Measurement(const Options& options) : options_(options) {}

  // The rest pose (body maps, hulls and spheres, peers), the mannequin's extra sections, then
  // (not --quick) the posed run.
  void RunCharacter(const CharacterSpec& spec);
  // speed_vs_error.csv, speed_vs_error.md and the charts in the output directory.
  void Finish();
  // The accuracy claims (checks.h) over every row measured.
  bool Check() const;

 private:
  // A character at one pose: its query sets and what the exact mesh answers to them.
  struct Context {
    CharacterSpec spec;
    size_t triangles = 0;
    const bake::MeshReference* reference = nullptr;
    std::vector<QuerySet> sets;  // the five sets, then "all"
    std::vector<std::vector<ReferenceAnswer>> answers;
    QuerySet peer_subset;  // every k-th motion of "all"
    std::vector<ReferenceAnswer> peer_answers;
  };
  // Hull assets kept for the posed run, by setting.
  using HullAssets = std::vector<std::pair<std::string, CharacterAsset>>;

  Context MakeContext(const CharacterSpec& spec, const std::vector<Float3>& positions,
                      const std::vector<uint32_t>& triangles, const bake::MeshReference& reference);
  Row MakeRow(const Context& c, const Method& m, const std::string& set, const Metrics& metrics);
  void Measure(const Context& c, const Method& method);
  void MeasurePeer(const Context& c, const Method& method);

  // Paper A at the rest pose: every body-map setting of the sweep. Returns the maps measured
  // with the default hulls beside them.
  std::unique_ptr<Method> MeasureRestMaps(const Context& context,
                                          const std::vector<Float3>& positions,
                                          const std::vector<uint32_t>& triangles);
  // Paper B at the rest pose: every hull bake of the sweep; the default bake also with the
  // runtime's variants, hulls and spheres alone, and with `default_maps`. Returns the assets the
  // posed run measures.
  HullAssets MeasureRestHulls(const Context& context, const bake::ImportOptions& import,
                              const std::vector<Mat34>& rest_skinning,
                              std::unique_ptr<Method> default_maps);
  void MeasureDefaultHullVariants(const Context& context, const CharacterAsset& a,
                                  const std::vector<Mat34>& rest_skinning, size_t bytes,
                                  const std::string& label, std::unique_ptr<Method> default_maps);
  void RunPosed(const CharacterSpec& spec, const bake::Character& character,
                const HullAssets& hull_assets);
  // At `fraction` of the clip, every joint turned by up to perturb_degrees on top (0: none).
  void RunPosedAt(const CharacterSpec& spec, const bake::Character& character,
                  const HullAssets& hull_assets, const ClipData& clip, float fraction,
                  float perturb_degrees = 0.f);
  // At a posed body: maps rendered from the skinned mesh, per-bone local maps, and the rest
  // pose's maps, which do not follow (following_maps.cpp).
  void MeasureFollowingMaps(const Context& context, const bake::Character& character,
                            std::span<const Mat34> skinning);

  // Report sections (measurement_sections.cpp).
  void ResolutionIndependence(const CharacterSpec& spec, const Context& base);
  void ClothSolvers(const CharacterSpec& spec, const bake::ImportOptions& import);

  const Options& options_;
  BodyMapViewAxis view_axis_ = BodyMapViewAxis::kZ;  // the character's least-air axis
  std::vector<Row> rows_;
  // Query-set contracts the mesh does not confirm, and humans measured taller than kTallestHuman.
  std::vector<std::string> set_violations_;
  std::vector<Section> sections_;
  std::vector<std::string> notes_;
  // The default bake's fit per character at rest (the report's "fit"), written to fit.csv.
  struct Fit {
    std::string character;
    double bloat_p99_mm, bloat_max_mm, coverage;
    size_t hulls;
  };
  std::vector<Fit> fits_;
};

}  // namespace drape::bench
