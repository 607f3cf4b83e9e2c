#include "asset_cache.h"

#include <unistd.h>

#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <vector>

#include "drape/bake/bake_config.h"
#include "drape/bake/bake_pipeline.h"
#include "drape/formats/asset_file.h"

namespace drape::sim {
namespace {

using nlohmann::json;

bool EndsWith(const std::string& s, const std::string& suffix) {
  if (s.size() < suffix.size()) return false;
  for (size_t i = 0; i < suffix.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(s[s.size() - suffix.size() + i])) != suffix[i])
      return false;
  }
  return true;
}

}  // namespace

Status HashFile(const std::string& path, std::string* hex) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status(StatusCode::kIoError, path + ": cannot read the character file");
  uint64_t hash = 0xcbf29ce484222325ull;  // FNV-1a offset basis
  std::vector<char> buffer(1 << 16);
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    const std::streamsize got = in.gcount();
    for (std::streamsize i = 0; i < got; ++i) {
      hash ^= static_cast<uint8_t>(buffer[static_cast<size_t>(i)]);
      hash *= 0x100000001b3ull;  // FNV prime
    }
  }
  char text[17];
  std::snprintf(text, sizeof(text), "%016llx", static_cast<unsigned long long>(hash));
  *hex = text;
  return Status::Ok();
}

Status LoadOrBakeAsset(const bake::Scene& scene, const std::string& directory, SceneAsset* out) {
  *out = SceneAsset{};
  if (EndsWith(scene.character, ".drape")) {
    out->path = scene.character;
    out->reason = "named by the scene";
    return ReadAssetFile(scene.character, &out->asset);
  }

  bake::BakeConfig config;
  if (Status s = bake::ApplySceneToBakeConfig(scene, &config); !s.ok()) return s;
  std::string hash;
  if (Status s = HashFile(scene.character, &hash); !s.ok()) return s;
  // The bake code is linked into this program: a rebuilt drape-sim may bake differently (the
  // format version does not change for that), so its own size and time are part of the key.
  std::string tool_build = DRAPE_VERSION_STRING;
  std::error_code error;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
  if (!error) {
    const auto size = std::filesystem::file_size(self, error);
    const auto time = std::filesystem::last_write_time(self, error);
    if (!error) {
      tool_build +=
          " " + std::to_string(size) + " " + std::to_string(time.time_since_epoch().count());
    }
  }
  const json key = {{"character_fnv1a64", hash},
                    {"bake_config", bake::BakeConfigToJson(config)},
                    {"format_version", kAssetFormatVersion},
                    {"tool_build", tool_build}};

  const std::string drape_path = directory + "/character.drape";
  const std::string key_path = directory + "/character.bake.json";
  out->path = drape_path;
  out->reason = "no cached asset";
  if (std::filesystem::exists(drape_path) && std::filesystem::exists(key_path)) {
    json stored;
    try {
      std::ifstream in(key_path);
      stored = json::parse(in);
    } catch (const json::exception&) {
      stored = json::object();
    }
    const json stored_key = stored.is_object() && stored.contains("key") ? stored["key"] : json();
    if (stored_key == key) {
      if (Status s = ReadAssetFile(drape_path, &out->asset); s.ok()) {
        out->reason = "cached";
        return Status::Ok();
      } else {
        out->reason = "the cached asset does not load (" + s.message() + ")";
      }
    } else if (!stored_key.is_object() || stored_key.value("character_fnv1a64", "") != hash) {
      out->reason = "the character file changed";
    } else {
      out->reason = "the bake configuration changed";
    }
  }

  const auto start = std::chrono::steady_clock::now();
  bake::BakeResult result;
  if (Status s = bake::BakeCharacter(scene.character, config, &result); !s.ok()) return s;
  out->bake_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  out->baked = true;
  out->report = std::move(result.report);
  out->asset = std::move(result.asset);
  // The asset first, then the key: a key never names an asset that was not written.
  std::remove(key_path.c_str());
  if (Status s = WriteAssetFile(drape_path, out->asset); !s.ok()) return s;
  const json record = {{"character", scene.character}, {"key", key}};
  if (Status s = WriteFileAtomically(key_path, record.dump(2) + "\n"); !s.ok()) return s;
  if (Status s = WriteFileAtomically(directory + "/bake_report.json", out->report.dump(2) + "\n");
      !s.ok())
    return s;
  return Status::Ok();
}

}  // namespace drape::sim
