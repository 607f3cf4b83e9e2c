// drape-bake INPUT -o OUT.drape [--config FILE.json] [--scene SCENE.json] [--report REPORT.json]
//            [--preview DIR] [--strict] [--depfile OUT.d] [--gltf OUT.gltf|.glb]
// drape-bake --batch MANIFEST.json [-j N] [--report SUMMARY.json] [--strict]
// drape-bake --dump-config
// On any error: one line on stderr naming the input and the reason, exit code 1, no output file.
// Warnings (what was assumed or repaired, colliders that fit the body badly) go to stderr, one
// line each, and into the report; with --strict any warning is an error: the line names the
// input, how many warnings there were and the first, and nothing is written.

#include <unistd.h>
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bake_batch.h"
#include "drape/bake/bake_config.h"
#include "drape/bake/bake_pipeline.h"
#include "drape/bake/gltf_export.h"
#include "drape/formats/asset_file.h"
#include "tasks/passive_waits.h"

namespace {

int Fail(const std::string& message) {
  std::fprintf(stderr, "drape-bake: error: %s\n", message.c_str());
  return 1;
}

// A path in a Makefile rule (what Ninja and Make read from a depfile): spaces and '#' escaped
// with a backslash, '$' doubled.
std::string MakeEscaped(const std::string& path) {
  std::string out;
  for (const char c : path) {
    if (c == ' ' || c == '#') out += '\\';
    if (c == '$') out += '$';
    out += c;
  }
  return out;
}

// "OUTPUT: input ...": the model and what it names, the config, the scene and its garment
// meshes, each once.
std::string DepfileRule(const std::string& output, std::vector<std::string> inputs) {
  std::string rule = MakeEscaped(output) + ":";
  std::vector<std::string> written;
  for (const std::string& input : inputs) {
    if (input.empty() || std::find(written.begin(), written.end(), input) != written.end())
      continue;
    written.push_back(input);
    rule += " \\\n  " + MakeEscaped(input);
  }
  return rule + "\n";
}

}  // namespace

int main(int argc, char** argv) {
  drape::detail::PreferPassiveOpenMpWaits(argv);  // tasks/passive_waits.h: why
  CLI::App app{
      "drape-bake: turns a rigged character (glTF, FBX, COLLADA, .X ...) into a .drape asset"};
  std::string input, output, config_path, scene_path, report_path, preview_dir, depfile_path;
  bool dump_config = false, list_formats = false, strict = false;
  std::string batch_manifest, gltf_path;
  unsigned jobs = 1;
  app.add_option("INPUT", input, "character file (anything assimp reads)");
  app.add_option("-o,--output", output, "the .drape file to write");
  app.add_option("--config", config_path, "JSON bake parameters (see --dump-config)");
  app.add_option("--scene", scene_path, "JSON scene: bake only what it needs");
  app.add_option("--report", report_path, "JSON report of the bake");
  app.add_option("--preview", preview_dir, "directory for preview pictures");
  app.add_flag("--strict", strict, "fail the bake on any warning (for pipelines)");
  app.add_option("--gltf", gltf_path,
                 "also write the asset as glTF 2.0 (.glb: binary) to look at: the skinned body, "
                 "the hulls and joint spheres on their joints, the clips");
  app.add_option("--depfile", depfile_path,
                 "write a Makefile-syntax dependency file (for Ninja and Make): the output and "
                 "every file the bake read");
  app.add_option("--batch", batch_manifest,
                 "bake every item of a JSON manifest ({\"items\": [{\"input\", \"output\", "
                 "\"config\", \"scene\", \"report\", \"depfile\", \"strict\"}]}, paths relative "
                 "to it), each in its own process; --report writes one summary");
  app.add_option("-j,--jobs", jobs, "with --batch: items baked at once")
      ->check(CLI::Range(1u, 256u));
  app.add_flag("--dump-config", dump_config, "print every parameter with default, unit and range");
  app.add_flag("--formats", list_formats, "print the file extensions the bake reads, one a line");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  if (dump_config) {
    std::printf("%s\n", drape::bake::BakeConfigReference().dump(2).c_str());
    return 0;
  }
  if (list_formats) {
    for (const std::string& extension : drape::bake::ReadableExtensions())
      std::printf("%s\n", extension.c_str());
    return 0;
  }
  if (!batch_manifest.empty()) {
    if (!input.empty() || !output.empty() || !config_path.empty() || !scene_path.empty() ||
        !preview_dir.empty() || !depfile_path.empty() || !gltf_path.empty())
      return Fail(batch_manifest +
                  ": --batch takes its inputs, outputs, configs and scenes from the manifest");
    std::error_code error;
    const std::string self = std::filesystem::read_symlink("/proc/self/exe", error).string();
    return drape::bake_tool::RunBatch(
        {batch_manifest, jobs, report_path, strict, error ? std::string(argv[0]) : self});
  }
  if (input.empty()) return Fail("no INPUT given (usage: drape-bake INPUT -o OUT.drape)");
  if (output.empty()) return Fail(input + ": no output given (-o OUT.drape)");
  drape::bake::BakeConfig config;
  if (!config_path.empty()) {
    if (drape::Status s = drape::bake::LoadBakeConfig(config_path, &config); !s.ok())
      return Fail(s.message());
  }
  // The scene decides the collider kinds and the clip; its own bake overrides come last.
  drape::bake::Scene scene;
  if (!scene_path.empty()) {
    if (drape::Status s = drape::bake::LoadScene(scene_path, &scene); !s.ok())
      return Fail(s.message());
    if (drape::Status s = drape::bake::ApplySceneToBakeConfig(scene, &config); !s.ok()) {
      return Fail(s.message());
    }
  }
  if (!preview_dir.empty()) {
    std::error_code error;
    std::filesystem::create_directories(preview_dir, error);
    if (error)
      return Fail(preview_dir + ": cannot create the preview directory: " + error.message());
  }
  const auto start = std::chrono::steady_clock::now();
  drape::bake::BakeResult result;
  if (drape::Status s = drape::bake::BakeCharacter(input, config, &result, preview_dir,
                                                   scene_path.empty() ? nullptr : &scene);
      !s.ok()) {
    return Fail(s.message());
  }
  const nlohmann::json& warnings = result.report["warnings"];
  if (strict && !warnings.empty()) {
    return Fail(input + ": --strict: " + std::to_string(warnings.size()) +
                (warnings.size() == 1 ? " warning: " : " warnings, the first: ") +
                warnings[0].get<std::string>());
  }

  std::vector<uint8_t> bytes;
  if (drape::Status s = drape::EncodeAsset(result.asset, &bytes); !s.ok())
    return Fail(input + ": " + s.message());
  result.report["output"] = output;
  const char* wait_policy = std::getenv("OMP_WAIT_POLICY");  // how the bake's threads waited
  result.report["openmp_wait_policy"] = wait_policy != nullptr ? wait_policy : "";
  result.report["output_bytes"] = bytes.size();
  result.report["timings"]["total_ms"] =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  // The glTF view, the dependency file and the report (each atomically), then the asset: a
  // failure at any step removes what was written before it, so no asset is left behind.
  std::vector<std::string> written;
  const auto write = [&](const std::string& path, const auto& write_file) {
    if (path.empty()) return true;
    if (drape::Status s = write_file(); !s.ok()) {
      for (const std::string& w : written) std::remove(w.c_str());
      Fail(s.message());
      return false;
    }
    written.push_back(path);
    return true;
  };
  std::vector<std::string> inputs = {input};
  inputs.insert(inputs.end(), result.input_files.begin(), result.input_files.end());
  inputs.push_back(config_path);
  inputs.push_back(scene_path);
  const bool ok =
      write(gltf_path, [&] { return drape::bake::WriteAssetGltf(result.asset, gltf_path); }) &&
      write(
          depfile_path,
          [&] { return drape::WriteFileAtomically(depfile_path, DepfileRule(output, inputs)); }) &&
      write(
          report_path,
          [&] { return drape::WriteFileAtomically(report_path, result.report.dump(2) + "\n"); }) &&
      write(output, [&] { return drape::WriteAssetFile(output, result.asset); });
  if (!ok) return 1;
  // What was assumed or repaired, one line each (also the report's "warnings").
  for (const auto& warning : warnings)
    std::fprintf(stderr, "drape-bake: warning: %s: %s\n", input.c_str(),
                 warning.get<std::string>().c_str());
  return 0;
}
