#pragma once
// The outputs of the measurement: speed_vs_error.csv (one row per character, method, setting and
// query set), speed_vs_error.md (the tables and the target checks) and a PNG chart per character
// through gnuplot (x: ns per particle, log; y: p99 penetration and missed rate; the Pareto front
// drawn; peers as vertical lines).

#include <string>
#include <vector>

#include "evaluation.h"

namespace drape::bench {

struct Row {
  std::string character;
  bool human = false;
  size_t triangles = 0;
  std::string family, setting, query_set;
  Metrics metrics;
  size_t baked_bytes = 0, runtime_bytes = 0;
  bool peer = false;
  bool pareto_penetration = false;  // on the front of (ns one thread, p99 penetration)
  bool pareto_missed = false;       // on the front of (ns one thread, missed rate)
};

// A free-form section appended to the markdown after the tables (per-bone hull distances,
// resolution independence, ...).
struct Section {
  std::string title;
  std::string body;  // markdown
};

// Marks the Pareto rows among each character's "all" rows with accuracy (peers excluded).
void MarkParetoFronts(std::vector<Row>* rows);

bool WriteCsv(const std::string& path, const std::vector<Row>& rows);
bool WriteMarkdown(const std::string& path, const std::vector<Row>& rows,
                   const std::vector<Section>& sections, const std::string& header);
// Writes <dir>/chart_<character>.dat and .gp and runs gnuplot when it is installed; the first
// character's chart is also written as <dir>/speed_vs_error.png. Returns the PNGs written.
std::vector<std::string> WriteCharts(const std::string& dir, const std::vector<Row>& rows);

// The headline targets per human character, as markdown; `ok` is false when a target
// fails (the message says which).
std::string TargetChecks(const std::vector<Row>& rows, bool* ok);

std::string FileSafe(const std::string& label);

}  // namespace drape::bench
