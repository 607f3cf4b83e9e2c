#pragma once
// drape-bake --batch MANIFEST.json [-j N] [--report SUMMARY.json] [--strict]: many characters,
// each baked by its own drape-bake process (a crash, hang or error stays with its item), at
// most N at a time, with one summary.

#include <string>

namespace drape::bake_tool {

struct BatchOptions {
  std::string manifest;      // JSON: {"items": [{"input", "output", "config", "scene", ...}]}
  unsigned jobs = 1;         // items baked at once, >= 1
  std::string summary_path;  // the summary report (empty: none)
  bool strict = false;       // every item fails on a warning
  std::string self;          // this drape-bake executable, run once per item
};

// Prints a line per item as it finishes and a last line with the counts; returns the exit code:
// 0 when every item baked, 1 when any failed or the manifest is bad (a line naming it and why,
// nothing baked).
int RunBatch(const BatchOptions& options);

}  // namespace drape::bake_tool
