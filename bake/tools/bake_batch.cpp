#include "bake_batch.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <vector>

#include "drape/formats/asset_file.h"

extern char** environ;

namespace drape::bake_tool {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

struct Item {
  std::string input, output, config, scene, report, depfile;
  bool strict = false;
};

struct Outcome {
  bool ok = false;
  std::string error;  // drape-bake's error line, or how the process ended
  double seconds = 0.0;
  int warnings = 0;
};

// A path of the manifest, resolved against its directory.
std::string Resolve(const fs::path& directory, const std::string& path) {
  return path.empty() || fs::path(path).is_absolute() ? path : (directory / path).string();
}

bool ParseItem(const json& j, const std::string& where, const fs::path& directory, Item* item,
               std::string* error) {
  if (!j.is_object()) {
    *error = where + ": not an object";
    return false;
  }
  static const char* kStrings[] = {"input", "output", "config", "scene", "report", "depfile"};
  std::string* fields[] = {&item->input, &item->output, &item->config,
                           &item->scene, &item->report, &item->depfile};
  for (const auto& [key, value] : j.items()) {
    if (key == "strict") {
      if (!value.is_boolean()) {
        *error = where + "/strict: must be true or false";
        return false;
      }
      item->strict = value.get<bool>();
      continue;
    }
    const auto* known = std::find(std::begin(kStrings), std::end(kStrings), key);
    if (known == std::end(kStrings)) {
      *error = where + "/" + key +
               ": unknown key (input, output, config, scene, report, "
               "depfile, strict)";
      return false;
    }
    if (!value.is_string() || value.get<std::string>().empty()) {
      *error = where + "/" + key + ": must be a non-empty path";
      return false;
    }
    *fields[known - std::begin(kStrings)] = Resolve(directory, value.get<std::string>());
  }
  if (item->input.empty() || item->output.empty()) {
    *error = where + ": needs \"input\" and \"output\"";
    return false;
  }
  return true;
}

bool ReadManifest(const std::string& path, std::vector<Item>* items, std::string* error) {
  std::ifstream in(path);
  if (!in) {
    *error = path + ": cannot open the manifest";
    return false;
  }
  const json j = json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("items") || !j["items"].is_array()) {
    *error = path + ": not a manifest (a JSON object with an \"items\" array)";
    return false;
  }
  const fs::path directory = fs::path(path).parent_path();
  std::map<std::string, size_t> outputs;
  for (size_t k = 0; k < j["items"].size(); ++k) {
    Item item;
    if (!ParseItem(j["items"][k], path + ": /items/" + std::to_string(k), directory, &item, error))
      return false;
    if (const auto [at, fresh] = outputs.emplace(item.output, k); !fresh) {
      *error = path + ": /items/" + std::to_string(k) + "/output: also the output of /items/" +
               std::to_string(at->second);
      return false;
    }
    items->push_back(item);
  }
  return true;
}

std::vector<std::string> BakeArguments(const BatchOptions& options, const Item& item) {
  std::vector<std::string> args = {options.self, item.input, "-o", item.output};
  for (const auto& [flag, value] :
       {std::pair{"--config", &item.config}, std::pair{"--scene", &item.scene},
        std::pair{"--report", &item.report}, std::pair{"--depfile", &item.depfile}}) {
    if (!value->empty()) {
      args.push_back(flag);
      args.push_back(*value);
    }
  }
  if (item.strict || options.strict) args.push_back("--strict");
  return args;
}

// Starts one item's drape-bake with its stderr to `log`; OMP_NUM_THREADS=1 when items run side
// by side (each would otherwise start a thread per core).
pid_t Start(const BatchOptions& options, const Item& item, const std::string& log) {
  std::vector<std::string> args = BakeArguments(options, item);
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::vector<std::string> env_strings;
  for (char** e = environ; *e != nullptr; ++e)
    if (options.jobs == 1 || std::string(*e).rfind("OMP_NUM_THREADS=", 0) != 0)
      env_strings.emplace_back(*e);
  if (options.jobs > 1) env_strings.emplace_back("OMP_NUM_THREADS=1");
  std::vector<char*> envp;
  for (std::string& e : env_strings) envp.push_back(e.data());
  envp.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, log.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  pid_t pid = -1;
  if (posix_spawn(&pid, options.self.c_str(), &actions, nullptr, argv.data(), envp.data()) != 0)
    pid = -1;
  posix_spawn_file_actions_destroy(&actions);
  return pid;
}

// The item's outcome from its exit status and its stderr lines.
Outcome Finish(int status, const std::string& log, double seconds) {
  Outcome outcome;
  outcome.seconds = seconds;
  std::ifstream in(log);
  std::string line;
  while (std::getline(in, line)) {
    if (line.find("drape-bake: warning:") == 0) ++outcome.warnings;
    if (line.find("drape-bake: error: ") == 0 && outcome.error.empty())
      outcome.error = line.substr(std::string("drape-bake: error: ").size());
  }
  outcome.ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
  if (!outcome.ok && outcome.error.empty()) {
    outcome.error = WIFSIGNALED(status)
                        ? "drape-bake ended by signal " + std::to_string(WTERMSIG(status))
                        : "drape-bake exited with " + std::to_string(WEXITSTATUS(status));
  }
  return outcome;
}

json Summary(const std::vector<Item>& items, const std::vector<Outcome>& outcomes) {
  json list = json::array();
  int failed = 0;
  for (size_t k = 0; k < items.size(); ++k) {
    json entry = {{"input", items[k].input},
                  {"output", items[k].output},
                  {"status", outcomes[k].ok ? "ok" : "failed"},
                  {"seconds", outcomes[k].seconds},
                  {"warnings", outcomes[k].warnings}};
    if (!outcomes[k].ok) entry["error"] = outcomes[k].error;
    failed += outcomes[k].ok ? 0 : 1;
    list.push_back(entry);
  }
  return {{"items", list}, {"baked", static_cast<int>(items.size()) - failed}, {"failed", failed}};
}

}  // namespace

int RunBatch(const BatchOptions& options) {
  std::vector<Item> items;
  std::string error;
  if (!ReadManifest(options.manifest, &items, &error)) {
    std::fprintf(stderr, "drape-bake: error: %s\n", error.c_str());
    return 1;
  }
  const fs::path logs = fs::temp_directory_path() / ("drape-batch-" + std::to_string(getpid()));
  fs::create_directories(logs);
  std::vector<Outcome> outcomes(items.size());
  std::map<pid_t, std::pair<size_t, Clock::time_point>> running;
  size_t next = 0, done = 0;
  while (done < items.size()) {
    while (next < items.size() && running.size() < options.jobs) {
      for (const std::string* file :
           {&items[next].output, &items[next].report, &items[next].depfile}) {
        std::error_code ignored;  // a directory that cannot be made fails the bake, which says so
        if (!file->empty()) fs::create_directories(fs::path(*file).parent_path(), ignored);
      }
      const std::string log = (logs / (std::to_string(next) + ".log")).string();
      const pid_t pid = Start(options, items[next], log);
      if (pid < 0) {
        outcomes[next] = {false, "cannot start " + options.self, 0.0, 0};
        ++done;
      } else {
        running[pid] = {next, Clock::now()};
      }
      ++next;
    }
    if (running.empty()) continue;
    int status = 0;
    const pid_t pid = waitpid(-1, &status, 0);
    const auto it = running.find(pid);
    if (it == running.end()) continue;
    const auto [k, start] = it->second;
    running.erase(it);
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    outcomes[k] = Finish(status, (logs / (std::to_string(k) + ".log")).string(), seconds);
    ++done;
    std::printf("drape-bake: batch [%zu/%zu] %s: %s\n", done, items.size(), items[k].input.c_str(),
                outcomes[k].ok
                    ? ("ok (" + std::to_string(outcomes[k].warnings) + " warnings)").c_str()
                    : ("FAILED: " + outcomes[k].error).c_str());
    std::fflush(stdout);
  }
  std::error_code ignored;
  fs::remove_all(logs, ignored);
  const json summary = Summary(items, outcomes);
  const int failed = summary["failed"].get<int>();
  std::printf("drape-bake: batch: %d baked, %d failed\n", summary["baked"].get<int>(), failed);
  if (!options.summary_path.empty()) {
    if (Status s = WriteFileAtomically(options.summary_path, summary.dump(2) + "\n"); !s.ok()) {
      std::fprintf(stderr, "drape-bake: error: %s\n", s.message().c_str());
      return 1;
    }
  }
  return failed == 0 ? 0 : 1;
}

}  // namespace drape::bake_tool
