#include "report.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace drape::bench {
namespace {

bool HasAccuracy(const Row& r) { return r.metrics.has_accuracy; }

std::string Fixed(double value, int digits) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.*f", digits, value);
  return buffer;
}

std::string Csv(const std::string& text) {
  if (text.find_first_of(",\"") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

std::string Bytes(size_t bytes) {
  if (bytes == 0) return "-";
  if (bytes >= 1u << 20) return Fixed(double(bytes) / double(1u << 20), 1) + " MiB";
  if (bytes >= 1u << 10) return Fixed(double(bytes) / double(1u << 10), 1) + " KiB";
  return std::to_string(bytes) + " B";
}

// Rows of one character's "all" set, in input order.
std::vector<const Row*> AllRows(const std::vector<Row>& rows, const std::string& character) {
  std::vector<const Row*> out;
  for (const Row& r : rows) {
    if (r.character == character && r.query_set == "all") out.push_back(&r);
  }
  return out;
}

std::vector<std::string> Characters(const std::vector<Row>& rows) {
  std::vector<std::string> names;
  for (const Row& r : rows) {
    if (std::find(names.begin(), names.end(), r.character) == names.end()) {
      names.push_back(r.character);
    }
  }
  return names;
}

const Row* FindPeer(const std::vector<const Row*>& rows, const std::string& prefix) {
  for (const Row* r : rows) {
    if (r->peer && r->setting.rfind(prefix, 0) == 0) return r;
  }
  return nullptr;
}

}  // namespace

std::string FileSafe(const std::string& label) {
  std::string out;
  for (char c : label) out += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return out;
}

void MarkParetoFronts(std::vector<Row>* rows) {
  for (Row& r : *rows) {
    if (r.query_set != "all" || r.peer || !HasAccuracy(r)) continue;
    bool dominated_penetration = false, dominated_missed = false;
    for (const Row& o : *rows) {
      if (&o == &r || o.character != r.character || o.query_set != "all" || o.peer ||
          !HasAccuracy(o)) {
        continue;
      }
      const double ns = o.metrics.ns_one_thread, my_ns = r.metrics.ns_one_thread;
      const auto dominates = [&](double mine, double theirs) {
        return ns <= my_ns && theirs <= mine && (ns < my_ns || theirs < mine);
      };
      dominated_penetration |=
          dominates(r.metrics.penetration_p99_mm, o.metrics.penetration_p99_mm);
      dominated_missed |= dominates(r.metrics.missed_rate, o.metrics.missed_rate);
    }
    r.pareto_penetration = !dominated_penetration;
    r.pareto_missed = !dominated_missed;
  }
}

bool WriteCsv(const std::string& path, const std::vector<Row>& rows) {
  std::ofstream out(path);
  out << "character,human,triangles,family,setting,query_set,queries,ns_per_particle_1t,"
         "ns_per_particle_2t,expected_contacts,missed,missed_rate,false_contact_rate,"
         "penetration_p99_mm,penetration_max_mm,contact_point_p50_mm,contact_point_p99_mm,"
         "normal_p50_deg,normal_p99_deg,own_surface_misses,baked_bytes,runtime_bytes,peer,"
         "pareto_penetration,pareto_missed\n";
  for (const Row& r : rows) {
    const Metrics& m = r.metrics;
    const bool a = m.has_accuracy;
    const auto acc = [&](double v, int digits) { return a ? Fixed(v, digits) : std::string(); };
    out << Csv(r.character) << ',' << (r.human ? 1 : 0) << ',' << r.triangles << ',' << r.family
        << ',' << Csv(r.setting) << ',' << r.query_set << ',' << m.queries << ','
        << Fixed(m.ns_one_thread, 2) << ',' << Fixed(m.ns_two_threads, 2) << ','
        << (a ? std::to_string(m.expected) : "") << ',' << (a ? std::to_string(m.missed) : "")
        << ',' << acc(m.missed_rate, 6) << ',' << acc(m.false_contact_rate, 6) << ','
        << acc(m.penetration_p99_mm, 3) << ',' << acc(m.penetration_max_mm, 3) << ','
        << acc(m.contact_point_p50_mm, 3) << ',' << acc(m.contact_point_p99_mm, 3) << ','
        << acc(m.normal_p50_deg, 2) << ',' << acc(m.normal_p99_deg, 2) << ','
        << (m.own_surface_misses >= 0 ? std::to_string(m.own_surface_misses) : "") << ','
        << r.baked_bytes << ',' << r.runtime_bytes << ',' << (r.peer ? 1 : 0) << ','
        << (r.pareto_penetration ? 1 : 0) << ',' << (r.pareto_missed ? 1 : 0) << '\n';
  }
  return static_cast<bool>(out);
}

std::string TargetChecks(const std::vector<Row>& rows, bool* ok) {
  std::ostringstream md;
  *ok = true;
  md << "| character | best body-map setting (p99 <= 2 mm, missed <= 0.1 %) | ns/particle | "
        "<= 25 ns | continuous hull settings with no own-surface miss | the cheapest of them | "
        "ns/particle | x exact (maps / hulls) | x FCL (maps / hulls) |\n"
        "|---|---|---|---|---|---|---|---|---|\n";
  for (const std::string& character : Characters(rows)) {
    const std::vector<const Row*> all = AllRows(rows, character);
    if (all.empty() || !all.front()->human) continue;
    const Row* best_maps = nullptr;
    const Row* best_hulls = nullptr;
    size_t clean_hulls = 0, hull_settings = 0;
    for (const Row* r : all) {
      const Metrics& m = r->metrics;
      if (!m.has_accuracy || r->peer) continue;
      if (r->family == "maps" && m.penetration_p99_mm <= 2.0 && m.missed_rate <= 0.001 &&
          (!best_maps || m.ns_one_thread < best_maps->metrics.ns_one_thread)) {
        best_maps = r;
      }
      // Discrete settings test the end position only: tunnelling is their documented limit.
      const bool discrete = r->setting.find("discrete") != std::string::npos;
      if ((r->family == "hulls+spheres" || r->family == "hulls") && !discrete) {
        ++hull_settings;
        if (m.own_surface_misses == 0) {
          ++clean_hulls;
          // The cheapest of them, as for the maps (the ratios' hull column).
          if (!best_hulls || m.ns_one_thread < best_hulls->metrics.ns_one_thread) best_hulls = r;
        }
      }
    }
    const Row* exact = FindPeer(all, "exact");
    const Row* fcl = FindPeer(all, "FCL");
    const auto ratio = [](const Row* peer, const Row* ours) {
      if (!peer || !ours || ours->metrics.ns_one_thread <= 0.0) return std::string("-");
      return Fixed(peer->metrics.ns_one_thread / ours->metrics.ns_one_thread, 0);
    };
    const bool fast = best_maps && best_maps->metrics.ns_one_thread <= 25.0;
    md << "| " << character << " | " << (best_maps ? best_maps->setting : "none") << " | "
       << (best_maps ? Fixed(best_maps->metrics.ns_one_thread, 1) : "-") << " | "
       << (fast ? "yes" : "**no**") << " | " << clean_hulls << " of " << hull_settings << " | "
       << (best_hulls ? best_hulls->setting : "none") << " | "
       << (best_hulls ? Fixed(best_hulls->metrics.ns_one_thread, 1) : "-") << " | "
       << ratio(exact, best_maps) << " / " << ratio(exact, best_hulls) << " | "
       << ratio(fcl, best_maps) << " / " << ratio(fcl, best_hulls) << " |\n";
    if (!best_maps || clean_hulls != hull_settings) *ok = false;
  }
  return md.str();
}

bool WriteMarkdown(const std::string& path, const std::vector<Row>& rows,
                   const std::vector<Section>& sections, const std::string& header) {
  std::ofstream out(path);
  out << header << "\n";
  bool targets_ok = true;
  out << "## Targets (human characters)\n\n" << TargetChecks(rows, &targets_ok) << "\n";
  for (const std::string& character : Characters(rows)) {
    const std::vector<const Row*> all = AllRows(rows, character);
    if (all.empty()) continue;
    out << "## " << character << " (" << all.front()->triangles << " triangles"
        << (all.front()->human ? ", human" : "") << ")\n\n"
        << "All query sets together (" << all.front()->metrics.queries
        << " motions). P: on the Pareto front of ns against p99 penetration / missed rate.\n\n"
        << "| family | setting | ns 1t | ns 2t | missed % | false % | p99 mm | max mm | "
           "point p50/p99 mm | normal p50/p99 deg | own misses | baked | P |\n"
        << "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n";
    for (const Row* r : all) {
      const Metrics& m = r->metrics;
      out << "| " << r->family << " | " << r->setting << " | " << Fixed(m.ns_one_thread, 1) << " | "
          << (m.ns_two_threads > 0 ? Fixed(m.ns_two_threads, 1) : "-") << " | ";
      if (m.has_accuracy) {
        out << Fixed(100.0 * m.missed_rate, 2) << " | " << Fixed(100.0 * m.false_contact_rate, 1)
            << " | " << Fixed(m.penetration_p99_mm, 2) << " | " << Fixed(m.penetration_max_mm, 1)
            << " | " << Fixed(m.contact_point_p50_mm, 2) << " / "
            << Fixed(m.contact_point_p99_mm, 1) << " | " << Fixed(m.normal_p50_deg, 1) << " / "
            << Fixed(m.normal_p99_deg, 0) << " | ";
      } else {
        out << "- | - | - | - | - | - | ";
      }
      out << (m.own_surface_misses >= 0 ? std::to_string(m.own_surface_misses) : "-") << " | "
          << Bytes(r->baked_bytes) << " | " << (r->pareto_penetration ? "p" : "")
          << (r->pareto_missed ? "m" : "") << " |\n";
    }
    // Time, missed rate and p99 per query set: what each kind of motion costs and loses.
    std::vector<std::string> set_names;
    for (const Row& r : rows) {
      if (r.character == character && r.query_set != "all" &&
          std::find(set_names.begin(), set_names.end(), r.query_set) == set_names.end()) {
        set_names.push_back(r.query_set);
      }
    }
    if (!set_names.empty()) {
      out << "\nns per particle (one thread) / missed rate (%) / p99 penetration (mm) per query "
             "set: what each kind of motion costs and loses:\n\n| setting |";
      for (const std::string& s : set_names) out << ' ' << s << " |";
      out << "\n|---|";
      for (size_t i = 0; i < set_names.size(); ++i) out << "---:|";
      out << '\n';
      for (const Row* a : all) {
        if (!a->metrics.has_accuracy) continue;
        out << "| " << a->family << ": " << a->setting << " |";
        for (const std::string& s : set_names) {
          for (const Row& r : rows) {
            if (r.character == character && r.setting == a->setting && r.family == a->family &&
                r.query_set == s) {
              out << ' ' << Fixed(r.metrics.ns_one_thread, 1) << " / "
                  << Fixed(100.0 * r.metrics.missed_rate, 2) << " / "
                  << Fixed(r.metrics.penetration_p99_mm, 1) << " |";
            }
          }
        }
        out << '\n';
      }
    }
    out << '\n';
  }
  for (const Section& s : sections) out << "## " << s.title << "\n\n" << s.body << "\n";
  return static_cast<bool>(out);
}

std::vector<std::string> WriteCharts(const std::string& dir, const std::vector<Row>& rows) {
  std::vector<std::string> written;
  const bool have_gnuplot = std::system("command -v gnuplot >/dev/null 2>&1") == 0;
  static const std::map<std::string, int> kFamilyStyle = {{"maps", 1},       {"hulls+spheres", 2},
                                                          {"hulls", 3},      {"spheres", 4},
                                                          {"maps+hulls", 5}, {"capsules", 6}};
  bool first = true;
  for (const std::string& character : Characters(rows)) {
    const std::vector<const Row*> all = AllRows(rows, character);
    const std::string base = dir + "/chart_" + FileSafe(character);
    double lo = 1e30, hi = 0.0;  // x range: our settings and the peers
    {
      std::ofstream dat(base + ".dat");
      dat << "# ns_1t p99_mm missed_pct style\n";
      std::vector<std::pair<double, double>> front_penetration, front_missed;
      for (const Row* r : all) {
        if (r->metrics.ns_one_thread > 0.0) {
          lo = std::min(lo, r->metrics.ns_one_thread);
          hi = std::max(hi, r->metrics.ns_one_thread);
        }
        if (r->peer || !r->metrics.has_accuracy) continue;
        const auto style = kFamilyStyle.find(r->family);
        // Log axis: a p99 of 0 is drawn at 0.001 mm.
        const double p99 = std::max(r->metrics.penetration_p99_mm, 0.001);
        const double missed = 100.0 * r->metrics.missed_rate;
        dat << r->metrics.ns_one_thread << ' ' << p99 << ' ' << missed << ' '
            << (style == kFamilyStyle.end() ? 6 : style->second) << '\n';
        if (r->pareto_penetration) front_penetration.push_back({r->metrics.ns_one_thread, p99});
        if (r->pareto_missed) front_missed.push_back({r->metrics.ns_one_thread, missed});
      }
      // The fronts as staircases sorted by speed (gnuplot breaks lines at filtered points).
      for (auto* front : {&front_penetration, &front_missed})
        std::sort(front->begin(), front->end());
      std::ofstream fp(base + "_front_p99.dat"), fm(base + "_front_missed.dat");
      for (const auto& [x, y] : front_penetration) fp << x << ' ' << y << '\n';
      for (const auto& [x, y] : front_missed) fm << x << ' ' << y << '\n';
    }
    const std::string png = base + ".png";
    {
      std::ofstream gp(base + ".gp");
      // noenhanced: names such as Animated_Human are text, not subscripts. In a single-quoted
      // gnuplot string a quote is written twice.
      std::string title;
      for (const char c : character) title += c == '\'' ? std::string("''") : std::string(1, c);
      gp << "set terminal pngcairo noenhanced size 1200,900 font 'sans,10'\n"
         << "set output '" << png << "'\n"
         << "set multiplot layout 2,1 title '" << title
         << ": speed against error (one marker per setting; line: Pareto front)'\n"
         << "set logscale x\nset grid\nset key outside right top\n"
         << "set xrange [" << lo / 1.5 << ":" << hi * 1.5 << "]\n"
         << "set xlabel 'ns per particle, one thread (log)'\n";
      std::string peers;
      for (const Row* r : all) {
        if (!r->peer || r->metrics.ns_one_thread <= 0.0) continue;
        const std::string name = r->setting.substr(0, r->setting.find(' '));
        peers += "set arrow from " + Fixed(r->metrics.ns_one_thread, 1) + ", graph 0 to " +
                 Fixed(r->metrics.ns_one_thread, 1) +
                 ", graph 1 nohead dt 2 lc rgb 'gray40'\nset label '" + name + "' at " +
                 Fixed(r->metrics.ns_one_thread, 1) +
                 ", graph 0.95 rotate by 90 right offset -1,0\n";
      }
      gp << peers;
      const char* families =
          "u 1:(column(4)==1?column(Y):1/0) w p pt 7 ps 1.2 lc rgb '#1f77b4' t 'body maps', "
          "'' u 1:(column(4)==2?column(Y):1/0) w p pt 5 ps 1.2 lc rgb '#d62728' t 'hulls + "
          "spheres', "
          "'' u 1:(column(4)==3?column(Y):1/0) w p pt 4 ps 1.2 lc rgb '#ff7f0e' t 'hulls alone', "
          "'' u 1:(column(4)==4?column(Y):1/0) w p pt 6 ps 1.2 lc rgb '#2ca02c' t 'joint spheres "
          "alone', "
          "'' u 1:(column(4)==5?column(Y):1/0) w p pt 9 ps 1.4 lc rgb '#9467bd' t 'maps + hulls', "
          "'' u 1:(column(4)==7?column(Y):1/0) w p pt 13 ps 1.3 lc rgb '#8c564b' t 'capsules'";
      gp << "Y=2\nset logscale y\nset ylabel 'p99 penetration after response, mm (log)'\n"
         << "plot '" << base << "_front_p99.dat' u 1:2 w steps lw 2 lc rgb 'black' t 'Pareto "
         << "front', '" << base << ".dat' " << families << "\n"
         << "Y=3\nunset logscale y\nset ylabel 'missed contacts, % (tunnelling included)'\n"
         << "plot '" << base << "_front_missed.dat' u 1:2 w steps lw 2 lc rgb 'black' t "
         << "'Pareto front', '" << base << ".dat' " << families << "\n"
         << "unset multiplot\n";
    }
    if (have_gnuplot && std::system(("gnuplot '" + base + ".gp' 2>/dev/null").c_str()) == 0) {
      written.push_back(png);
      if (first) {
        std::ifstream in(png, std::ios::binary);
        std::ofstream out(dir + "/speed_vs_error.png", std::ios::binary);
        out << in.rdbuf();
        written.push_back(dir + "/speed_vs_error.png");
      }
    }
    first = false;
  }
  return written;
}

}  // namespace drape::bench
