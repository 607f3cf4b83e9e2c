// drape-sim SCENE.json -o DIR [--frames N] [--threads T]
// drape-sim --dump-scene-reference   (docs/SCENES.md: every scene field, from the parser's schema)
// Bakes the scene's character when its cached asset is missing or stale, simulates the garments
// against the colliders the scene names, and writes DIR/frames/frame_NNNN.png (NNNN: the
// simulation frame), an animation (DIR/animation.mp4 or .gif through ffmpeg when it is on PATH,
// else DIR/contact_sheet.png), optionally DIR/obj/<garment>_NNNN.obj, DIR/stats.json and
// DIR/reach.json.
// Progress goes to stderr (a bar on a terminal, else a line per 10 %), log lines to stdout. On
// any error: one line on stderr naming the input and the reason, exit code 1.

#include <CLI/CLI.hpp>
#include <cstdio>

#include "drape/bake/scene.h"
#include "run_scene.h"
#include "tasks/passive_waits.h"

int main(int argc, char** argv) {
  drape::detail::PreferPassiveOpenMpWaits(argv);  // tasks/passive_waits.h: why
  CLI::App app{
      "drape-sim: bakes a scene's character if needed, simulates its garments and "
      "writes pictures and figures"};
  drape::sim::RunOptions options;
  bool dump_reference = false;
  app.add_option("SCENE", options.scene_path, "the scene JSON (see docs/SCENES.md)");
  app.add_option("-o,--output", options.out_dir, "output directory (created)");
  app.add_option("--frames", options.frames, "frames to simulate (overrides the scene's duration)")
      ->check(CLI::Range(int64_t{1}, int64_t{10000000}));
  app.add_option("--threads", options.threads,
                 "worker threads: the cloth step's task pool and the bake's OpenMP team (default: "
                 "all cores)")
      ->check(CLI::Range(1, 1024));
  app.add_option("--gltf", options.gltf_path,
                 "also write the run as one animated glTF 2.0 (.glb: binary): the body skinned by "
                 "the played poses, each garment's frames as morph targets (at most 300 frames, "
                 "evenly spread over the written ones)");
  app.add_option("--export-garments", options.garments_dir,
                 "also write each garment as DIR/<garment>.glb: the character and the garment "
                 "skinned to its skeleton (its skin weights, or its carrier joint's), with max "
                 "distance (0 where a joint holds it) and backstop as _MAX_DISTANCE / _BACKSTOP, "
                 "to paint and read back as a `gltf` garment");
  app.add_flag("--dump-scene-reference", dump_reference,
               "print the scenes reference (docs/SCENES.md) as markdown and exit");
  try {
    app.parse(argc, argv);
    if (dump_reference) {
      std::fputs(drape::bake::SceneReferenceMarkdown().c_str(), stdout);
      return 0;
    }
    if (options.scene_path.empty()) throw CLI::RequiredError("SCENE");
    if (options.out_dir.empty()) throw CLI::RequiredError("--output");
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  return drape::sim::RunScene(options);
}
