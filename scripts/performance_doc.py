#!/usr/bin/env python3
"""Writes PERFORMANCE.md from one run of the bench command (scripts/bench.sh).

Reads what scripts/bench.sh leaves in its output directory (default out/bench):
  run_info.txt            machine, command, commit and load of the run (written by bench.sh)
  speed_vs_error.csv/.md  drape-speed-vs-error: every method and setting, and its sections
  chart_<character>.png   the speed-against-error charts
  gbench/bench_*.json     Google Benchmark's JSON output (scripts/bench.sh --gbench)
and writes <out>/PERFORMANCE.md in the shape of docs/PERFORMANCE.md, with the charts it shows
copied to <out>/images/speed_vs_error_<character>.png. Adopt a run with
  cp out/bench/PERFORMANCE.md docs/ && cp out/bench/images/*.png docs/images/
Only the Python standard library; the prose is fixed here, every figure comes from the run.
"""

import argparse
import csv
import os
import platform
import re
import shutil
import subprocess
import sys

sys.dont_write_bytecode = True  # no __pycache__ beside the scripts

from performance_doc_format import (Doc, file_safe, mm, ns, number, pair,  # noqa: E402
                                    pct, size, span)
from performance_doc_gbench import (body_map_bake, body_map_queries, cloth,  # noqa: E402
                                    following_maps, hull_bake, hull_queries, read_gbench, shapes)

# A run that starts with a 1-minute load average at or above this shares the machine.
LOADED = 1.0
# The accuracy target of a body-map setting (drape-speed-vs-error --check holds humans to it).
MAX_MISSED = 0.001  # fraction of the motions that expect a contact
MAX_P99_MM = 2.0
TARGET_NS = 25.0  # ns per particle, one thread


# ------------------------------------------------------------------------------------------
# Reading the run


def read_run_info(out):
    info = {}
    path = os.path.join(out, "run_info.txt")
    if os.path.exists(path):
        with open(path, encoding="utf-8") as f:
            for line in f:
                key, sep, value = line.rstrip("\n").partition("=")
                if sep:
                    info[key] = value
    else:  # a directory written by hand: describe this machine and say the command is unknown
        info["command"] = "unknown (no run_info.txt)"
        info["cpu"] = platform.processor() or "unknown CPU"
        if os.path.exists("/proc/cpuinfo"):
            with open("/proc/cpuinfo", encoding="utf-8") as f:
                models = [line.split(":", 1)[1].strip() for line in f
                          if line.startswith("model name")]
            info["cpu"] = models[0] if models else info["cpu"]
        info["cores"] = str(os.cpu_count())
    if "commit" not in info:
        try:
            info["commit"] = subprocess.run(
                ["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                check=True).stdout.strip()
        except (OSError, subprocess.CalledProcessError):
            info["commit"] = "unknown"
    return info


def read_rows(out):
    path = os.path.join(out, "speed_vs_error.csv")
    if not os.path.exists(path):
        return []
    rows = []
    with open(path, newline="", encoding="utf-8") as f:
        for r in csv.DictReader(f):
            if r["query_set"] != "all":
                continue
            for key in ("ns_per_particle_1t", "ns_per_particle_2t", "missed_rate",
                        "false_contact_rate", "penetration_p99_mm", "penetration_max_mm",
                        "normal_p50_deg", "own_surface_misses", "baked_bytes"):
                r[key] = number(r[key])
            r["peer"] = r["peer"] == "1"
            r["human"] = r["human"] == "1"
            r["pareto"] = r["pareto_penetration"] == "1" or r["pareto_missed"] == "1"
            r["base"], _, pose = r["character"].partition(" posed (")
            r["posed"] = pose.rstrip(")")
            rows.append(r)
    # The tables show each character at rest and in its first measured pose; the CSV holds the
    # others (the full sweep poses characters at 40 % and 80 % of their longest clip).
    first_pose = {}
    for r in rows:
        if r["posed"]:
            first_pose.setdefault(r["base"], r["posed"])
    return [r for r in rows if not r["posed"] or r["posed"] == first_pose[r["base"]]]


def read_proxy_rows(out):
    """{character at rest: {query set: row}} of the default hulls and joint colliders."""
    path = os.path.join(out, "speed_vs_error.csv")
    proxies = {}
    if not os.path.exists(path):
        return proxies
    with open(path, newline="", encoding="utf-8") as f:
        for r in csv.DictReader(f):
            if (r["family"] == "hulls+spheres" and r["setting"].startswith("default (")
                    and r["setting"].endswith("spheres)") and " posed (" not in r["character"]):
                proxies.setdefault(r["character"], {})[r["query_set"]] = r
    return proxies


def read_sections(out):
    """The '## title' sections of speed_vs_error.md, by title."""
    path = os.path.join(out, "speed_vs_error.md")
    sections = {}
    if os.path.exists(path):
        title = None
        with open(path, encoding="utf-8") as f:
            for line in f:
                if line.startswith("## "):
                    title = line[3:].strip()
                    sections[title] = []
                elif title is not None:
                    sections[title].append(line.rstrip("\n"))
    return {t: "\n".join(lines).strip() for t, lines in sections.items()}


# ------------------------------------------------------------------------------------------
# Choosing the rows that matter


def has_accuracy(r):
    return r["missed_rate"] is not None and not r["peer"]


def passes(r):
    return (r["family"] == "maps" and has_accuracy(r) and r["missed_rate"] <= MAX_MISSED
            and r["penetration_p99_mm"] <= MAX_P99_MM)


def lane_variant(r):  # the same maps with the batch kept to narrower lanes
    return "SSE2 lanes" in r["setting"] or "scalar lanes" in r["setting"]


def default_maps(r):  # the bake's default body maps (bake config: N = 1024, four layers)
    return r["family"] == "maps" and r["setting"] == "N=1024 nearest layers=4"


def default_hulls(r):  # the bake's default hulls and joint spheres, default runtime options
    return (r["family"] == "hulls+spheres" and r["setting"].startswith("default")
            and r["setting"].endswith("spheres)"))


def clean_continuous_hulls(r):
    return (r["family"] in ("hulls", "hulls+spheres") and "discrete" not in r["setting"]
            and r["own_surface_misses"] == 0)


def cheapest(rows, keep):
    chosen = [r for r in rows if keep(r) and r["ns_per_particle_1t"]]
    return min(chosen, key=lambda r: r["ns_per_particle_1t"]) if chosen else None


def by_character(rows):
    """{character label: rows}, each character at rest followed by its posed body."""
    characters = {}
    for r in rows:
        characters.setdefault(r["character"], []).append(r)
    ordered = {}
    for c, rs in characters.items():
        if not rs[0]["posed"]:
            ordered[c] = rs
            for p, ps in characters.items():
                if ps[0]["posed"] and ps[0]["base"] == c:
                    ordered[p] = ps
    for c, rs in characters.items():  # a posed body without its rest pose
        ordered.setdefault(c, rs)
    return ordered


def peer(rows, prefix):
    return next((r for r in rows if r["peer"] and r["setting"].startswith(prefix)), None)


def ratio(reference, ours):
    if not reference or not ours or not ours["ns_per_particle_1t"]:
        return "-"
    return f"{reference['ns_per_particle_1t'] / ours['ns_per_particle_1t']:.0f}x"


# ------------------------------------------------------------------------------------------
# The document


def header(doc, rows):
    i = doc.info
    doc.add("# Performance", "")
    load = (i.get("load_start") or "").split()
    if load and number(load[0]) is not None and number(load[0]) >= LOADED:
        end = (i.get("load_end") or "").split()
        doc.add(f"> **Figures from a loaded machine** (load average {load[0]} when the run "
                f"started{', ' + end[0] + ' at its end' if end else ''}): they are upper bounds. "
                "Regenerate them on an idle machine.", "")
    if i.get("quick") == "1":
        doc.add("> **Quick sweep** (`--quick`): fewer settings, 1 000 motions per query set, no "
                "posed bodies. The full sweep is `scripts/bench.sh --gbench`.", "")
    doc.add(
        "The current figures, written by `scripts/performance_doc.py` from one run of the bench "
        "command. Regenerate them with `scripts/bench.sh --gbench` on an idle machine, then `cp "
        "out/bench/PERFORMANCE.md docs/ && cp "
        "out/bench/images/*.png docs/images/`. What each method computes is in "
        "`docs/ALGORITHMS.md`; how the errors are defined in its §12.", "",
        f"Run: {doc.machine()}; OpenMP `{i.get('omp', '?')}`; commit `{i.get('commit', '?')}`"
        f"{' with local changes' if i.get('worktree') == 'modified' else ''}; {i.get('date', '')}."
        " Times vary by about ±10–20 % between runs on a shared VM; compare settings within one "
        "run. Where other work shares the cores, run with `OMP_WAIT_POLICY=passive`: spinning "
        "OpenMP waits make two-thread figures many times slower whenever another process holds "
        "a core.", "")


def needs(doc, rows):
    doc.add("## Which setting for which need", "",
            "ns: per particle, the batch call with response, one thread / two, over the "
            "characters named (rest pose and, in the full sweep, posed). Errors against the exact "
            "posed mesh: missed contacts and p99 penetration after response.", "",
            "| need | method and setting | ns per particle | error |", "|---|---|---|---|")
    characters = by_character(rows)
    humans = {c: rs for c, rs in characters.items() if rs[0]["human"]}
    others = {c: rs for c, rs in characters.items() if not rs[0]["human"] and not rs[0]["posed"]}

    def row(need, setting, chosen, note=""):
        if not chosen:
            return
        t1 = span([r["ns_per_particle_1t"] for r in chosen], ns)
        t2 = span([r["ns_per_particle_2t"] for r in chosen], ns)
        acc = [r for r in chosen if has_accuracy(r)]
        error = ("missed " + span([r["missed_rate"] for r in acc], pct) + " %, p99 " +
                 span([r["penetration_p99_mm"] for r in acc], mm) + " mm") if acc else note
        doc.add(f"| {need} | {setting} | {t1} / {t2} | {error} |")

    best = [cheapest(rs, passes) for rs in humans.values()]
    best = [r for r in best if r]
    if best:
        names = sorted({r["setting"] for r in best})
        row("cheapest collision for people (p99 ≤ 2 mm, missed ≤ 0.1 %)",
            "body maps, per body: " + ", ".join(names) + " (targets table below)", best)
    # One body-map setting that passes on every human at rest and posed: the least worst time.
    settings = {}
    for c, rs in humans.items():
        for r in rs:
            if r["family"] == "maps" and not lane_variant(r):
                settings.setdefault(r["setting"], {})[c] = r
    universal = [s for s, by in settings.items()
                 if len(by) == len(humans) and all(passes(r) for r in by.values())]
    if universal:
        pick = min(universal, key=lambda s: max(r["ns_per_particle_1t"]
                                                for r in settings[s].values()))
        row("one body-map setting for every person and pose", f"body maps {pick}",
            list(settings[pick].values()))
    for c, rs in others.items():
        r = cheapest(rs, passes)
        if r:
            row(f"a non-human body: {c}", f"body maps {r['setting']}", [r])
        else:
            maps = [r for r in rs if r["family"] == "maps" and has_accuracy(r)]
            if maps:
                r = min(maps, key=lambda r: (r["missed_rate"], r["ns_per_particle_1t"]))
                row(f"a non-human body: {c} (no setting meets the target)",
                    f"body maps {r['setting']} (fewest misses)", [r])
    combined = [r for r in rows if r["family"] == "maps+hulls"]
    if combined:
        row("cloth that must never sink in, any body", "body maps + default hulls (" +
            ", ".join(sorted({r["setting"] for r in combined})) + ")", combined)
    people = [r for rs in humans.values() for r in rs]
    row("skeleton-driven proxies, no maps (people)", "default hulls + joint spheres (100 "
        "triangles, δ 5 mm, plane test, push-out)", [r for r in people if default_hulls(r)])
    row("paper B as written (people)", "default hulls + joint spheres, Kirkpatrick + map-table "
        "ray", [r for r in people if r["setting"].endswith("(paper B)")])
    row("the exact answer (reference)", "winding number + CGAL AABB tree",
        [r for r in rows if r["peer"] and r["setting"].startswith("exact")], "exact")


def charts(doc, characters):
    """The charts of the characters at rest, four to a row, copied to <out>/images/."""
    shown = []
    for c, rs in characters.items():
        src = os.path.join(doc.out, f"chart_{file_safe(c)}.png")
        if rs[0]["posed"] or not os.path.exists(src):
            continue
        name = f"speed_vs_error_{file_safe(c)}.png"
        os.makedirs(os.path.join(doc.out, "images"), exist_ok=True)
        shutil.copyfile(src, os.path.join(doc.out, "images", name))
        shown.append((c, name))
    for first in range(0, len(shown), 4):
        group = shown[first:first + 4]
        doc.add("| " + " | ".join(c for c, _ in group) + " |", "|" + "---|" * len(group),
                "| " + " | ".join(f"![speed against error, {c}](images/{n})" for c, n in group)
                + " |", "")


def speed_vs_error(doc, rows, sections):
    doc.add("## Speed against error", "",
            "`drape-speed-vs-error` runs every method and setting on the same seeded motions of "
            "each character (uniform points, near-surface points, thin crossings, fast segments, "
            "particles started inside) and compares the answers with the exact posed mesh. "
            "*ns*: `CollideBatch` with response, per particle, the fastest of 5 timed runs (3 in "
            "the quick sweep). *missed*: contacts the mesh expects that the method does not "
            "report, tunnelling included. *p99*: penetration after response. *false*: contacts "
            "where the mesh has none (the 5 mm ε and δ inflations cause most of them by design). "
            "Humans taller than 2.5 m at rest are measured rescaled to 1.75 m. "
            "`speed_vs_error.csv` and `.md` in the output directory hold every row and the "
            "per-set breakdown.", "")
    characters = by_character(rows)
    humans = [c for c, rs in characters.items() if rs[0]["human"]]
    if humans:
        doc.add("### Targets (people)", "",
                "The cheapest body-map setting with p99 ≤ 2 mm and missed ≤ 0.1 %, against "
                f"≤ {TARGET_NS:.0f} ns per particle at one thread and ≥ 1000x / ≥ 300x the "
                "exact query / FCL (ratios within this run; FCL at rest only). The exact "
                "query's cost grows with the triangle count and the maps' does not, so the "
                "ratios favour finely meshed bodies. The hull column is the cheapest continuous "
                "hull setting that lets no motion into its own surface.", "",
                "| character | body maps | ns | missed %, p99 mm | x exact | x FCL | hulls | ns "
                "| x exact | x FCL |", "|---|---|---|---|---|---|---|---|---|---|")
        for c in humans:
            rs = characters[c]
            m, h = cheapest(rs, passes), cheapest(rs, clean_continuous_hulls)
            exact, fcl = peer(rs, "exact"), peer(characters.get(rs[0]["base"], rs), "FCL")
            t = "-"
            if m:
                t = f"{ns(m['ns_per_particle_1t'])} / {ns(m['ns_per_particle_2t'])}"
                if m["ns_per_particle_1t"] > TARGET_NS:
                    t = f"**{t}**"
            doc.add(f"| {c} | {m['setting'] if m else '**none**'} | {t} | "
                    f"{pct(m['missed_rate']) + ', ' + mm(m['penetration_p99_mm']) if m else '-'} "
                    f"| {ratio(exact, m)} | {ratio(fcl, m)} | {h['setting'] if h else 'none'} | "
                    f"{ns(h['ns_per_particle_1t']) if h else '-'} | {ratio(exact, h)} | "
                    f"{ratio(fcl, h)} |")
        doc.source("speed against error")

    proxy_targets(doc, read_proxy_rows(doc.out), read_fits(doc.out))
    doc.add("### Charts", "",
            "x: ns per particle at one thread (log); y: p99 penetration after response and the "
            "missed rate; one marker per setting, the line is the Pareto front, dashed lines the "
            "peers.", "")
    charts(doc, characters)
    characters_table(doc, characters)
    lanes(doc, characters)
    peers(doc, characters)
    for title in ("Paper A's claim: collision cost independent of body resolution",):
        if title in sections:
            doc.add(f"### {title}", "", sections[title])
            doc.source("speed against error")


def lanes(doc, characters):
    """What the wider lanes buy: the same maps with the batch kept to narrower lanes."""
    variants = [v for v in ("SSE2 lanes", "scalar lanes")
                if any(v in r["setting"] for rs in characters.values() for r in rs)]
    if not variants:
        return
    bases = []  # the settings measured with narrower lanes, in sweep order
    for rs in characters.values():
        for r in rs:
            for v in variants:
                if r["setting"].endswith(" " + v):
                    base = r["setting"][:-len(v) - 1]
                    if base not in bases:
                        bases.append(base)
    for c, rs in characters.items():
        if rs[0]["posed"] or not rs[0]["human"]:
            continue
        settings = {r["setting"]: r for r in rs if r["family"] == "maps"}
        cells = []
        for base in bases:
            found = [settings.get(base)] + [settings.get(f"{base} {v}") for v in variants]
            cells.append(base + ": " + " / ".join(ns(r["ns_per_particle_1t"]) if r else "-"
                                                   for r in found))
        doc.add("### Body-map batch lanes", "",
                "The same maps and motions with `CollideBatch` kept to narrower lanes give the "
                f"same bits; ns per particle at one thread on the {c} at rest, the widest the CPU "
                "has / " + " / ".join(variants) + " (the plain C++ reference pack): "
                + "; ".join(cells) + ".", "")
        break
    doc.source("speed against error")


def key_rows(rs):
    """The rows of one character at rest that matter, each with why it is shown."""
    tags = {}

    def tag(r, text):
        if r:
            tags.setdefault(id(r), (r, []))[1].append(text)

    # The fastest point that misses under half the contacts (joint spheres alone are always the
    # fastest and miss 90 % of them) and the most accurate point of the fronts.
    front = sorted((r for r in rs if r["pareto"] and not lane_variant(r)
                    and r["missed_rate"] is not None and r["missed_rate"] < 0.5),
                   key=lambda r: r["ns_per_particle_1t"])
    if front:
        tag(front[0], "P")
    for r in rs:
        if default_maps(r) or default_hulls(r):
            tag(r, "default")
        if r["family"] == "capsules":
            tag(r, "capsules")
    tag(cheapest(rs, passes), "cheapest passing")
    if front:  # the most accurate point, unless a row already shown is as accurate
        accuracy = lambda r: (r["missed_rate"], r["penetration_p99_mm"])  # noqa: E731
        best = min(front, key=accuracy)
        shown = [r for r, _ in tags.values() if r["missed_rate"] is not None
                 and r["penetration_p99_mm"] is not None]
        if id(best) in tags or all(accuracy(best) < accuracy(r) for r in shown):
            tag(best, "P")
    return sorted(tags.values(), key=lambda t: t[0]["ns_per_particle_1t"] or 0)


def read_fits(out):
    """{character: row of fit.csv}: the default bake's bloat and coverage."""
    path = os.path.join(out, "fit.csv")
    if not os.path.exists(path):
        return {}
    with open(path, newline="", encoding="utf-8") as f:
        return {r["character"]: r for r in csv.DictReader(f)}


def proxy_targets(doc, proxies, fits):
    if not proxies:
        return
    doc.add("### Proxy colliders (hulls + joint colliders, defaults, rest pose)", "",
            "Targets: motions that start clear of the body (thin crossings, fast segments) missed "
            "≤ 0.5 %; penetration after the response p99 ≤ 5 mm, max ≤ 20 mm; ≤ 150 ns per "
            "particle on people; the colliders' bloat (how far their surface reaches outside the "
            "body beyond delta, from the bake report's `fit`) p99 ≤ 10 mm, max ≤ 30 mm, and "
            "coverage ≥ 99 %. A person whose file makes them taller than a person is rescaled "
            "to 1.75 m; the others are as their files give them (the Spider 5.9 m long). Bold: "
            "not met.", "",
            "| character | colliders | bloat p99 / max mm | coverage % | missed % thin / fast "
            "| p99 / max mm thin + fast | ns 1t |",
            "|---|---|---|---|---|---|---|")
    for c, sets in proxies.items():
        thin, fast, every = sets.get("thin_crossing"), sets.get("fast"), sets.get("all")
        if not (thin and fast and every):
            continue
        missed = [float(thin["missed_rate"]) * 100, float(fast["missed_rate"]) * 100]
        p99 = max(float(thin["penetration_p99_mm"]), float(fast["penetration_p99_mm"]))
        worst = max(float(thin["penetration_max_mm"]), float(fast["penetration_max_mm"]))
        speed = float(every["ns_per_particle_1t"])
        bold = lambda text, bad: f"**{text}**" if bad else text  # noqa: E731
        counts = every["setting"].rsplit("(", 1)[-1].rstrip(")")
        fit = fits.get(c)
        if fit:
            bloat = [float(fit["bloat_p99_mm"]), float(fit["bloat_max_mm"])]
            coverage = float(fit["coverage"]) * 100
            too_far = bloat[0] > 10 or bloat[1] > 30
            fit_cells = (f"{bold(f'{bloat[0]:.1f} / {bloat[1]:.1f}', too_far)}"
                         f" | {bold(f'{coverage:.2f}', coverage < 99)}")
        else:
            fit_cells = "- | -"
        doc.add(f"| {c} | {counts} | {fit_cells} | "
                f"{bold(f'{missed[0]:.2f} / {missed[1]:.2f}', max(missed) > 0.5)} | "
                f"{bold(f'{p99:.1f} / {worst:.1f}', p99 > 5 or worst > 20)} | "
                f"{bold(ns(speed), every['human'] == '1' and speed > 150)} |")
    doc.source("speed against error")


def characters_table(doc, characters):
    doc.add("### Every character", "",
            "Per character at rest: the fastest point of the Pareto fronts missing under half the "
            "contacts and the most accurate one (P), the bake's defaults and the cheapest setting "
            "meeting the body-map target; maps with hulls and the posed bodies are in "
            "speed_vs_error.csv.", "",
            "| character | method | setting | ns 1t / 2t | missed % | p99 mm | false % | normal "
            "p50 ° | baked | why |", "|---|---|---|---|---|---|---|---|---|---|")
    for c, rs in characters.items():
        if rs[0]["posed"]:
            continue  # posed bodies: "Maps that follow any pose" and speed_vs_error.csv
        name = c.replace(" posed (", ", posed (") if rs[0]["posed"] else c
        for r, why in key_rows(rs):
            doc.add(f"| {name} | {r['family']} | {r['setting']} | {ns(r['ns_per_particle_1t'])} / "
                    f"{ns(r['ns_per_particle_2t'])} | {pct(r['missed_rate'])} | "
                    f"{mm(r['penetration_p99_mm'])} | {pct(r['false_contact_rate'], 1)} | "
                    f"{mm(r['normal_p50_deg'])} | {size(r['baked_bytes'])} | {', '.join(why)} |")
    doc.source("speed against error")


def peers(doc, characters):
    doc.add("### Peers", "",
            "The exact mesh query (generalised winding number at both ends, first crossing by "
            "CGAL's AABB tree) and FCL's BVH point distance (OBBRSS; speed only), timed as the "
            "methods are on a subset of the same motions at rest: ns per particle, one thread / "
            "two.", "",
            "| character | triangles | exact mesh query | FCL distance |", "|---|---|---|---|")
    for c, rs in characters.items():
        if rs[0]["posed"]:
            continue  # the posed bodies' exact query is in the targets' ratios
        times = [pair(r["ns_per_particle_1t"], r["ns_per_particle_2t"]) if r else "-"
                 for r in (peer(rs, "exact"), peer(rs, "FCL"))]
        if times != ["-", "-"]:
            doc.add(f"| {c} | {rs[0]['triangles']} | {times[0]} | {times[1]} |")
    doc.source("speed against error")


def footer(doc, gb):
    if not gb:
        doc.add("## Microbenchmarks", "",
                "Not run: `scripts/bench.sh --gbench` adds the body-map and hull query, cloth "
                "step and bake benchmarks.", "")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/bench", help="the bench command's output directory")
    args = parser.parse_args()
    info = read_run_info(args.out)
    rows = read_rows(args.out)
    sections = read_sections(args.out)
    gb = read_gbench(args.out) if info.get("gbench", "1") == "1" else {}
    images = os.path.join(args.out, "images")
    if os.path.isdir(images):
        shutil.rmtree(images)
    doc = Doc(info, args.out)
    header(doc, rows)
    if rows:
        needs(doc, rows)
        doc.add("")
        speed_vs_error(doc, rows, sections)
    body_map_queries(doc, gb)
    following_maps(doc, gb, rows)
    hull_queries(doc, gb)
    cloth(doc, gb, sections)
    shapes(doc, gb)
    body_map_bake(doc, gb)
    hull_bake(doc, gb)
    footer(doc, gb)
    text = re.sub(r"\n{3,}", "\n\n", "\n".join(doc.lines).rstrip() + "\n")
    path = os.path.join(args.out, "PERFORMANCE.md")
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
    lines = text.count("\n")
    print(f"performance_doc: wrote {path} ({lines} lines)")
    if lines >= 300:
        print(f"performance_doc: {path} has {lines} lines; the document is meant to stay under "
              "300: show fewer rows", file=sys.stderr)


if __name__ == "__main__":
    main()
