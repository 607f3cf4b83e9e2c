"""The Google Benchmark tables of PERFORMANCE.md (scripts/performance_doc.py): reads the JSON that
scripts/bench.sh --gbench writes (median aggregates) and writes one table per program."""

import json
import math
import os
import re
import sys

from performance_doc_format import mm, ns, pair, span


def read_gbench(out):
    """{program: {(benchmark, (args...)): entry}}: the median aggregates (or single runs)."""
    programs = {}
    directory = os.path.join(out, "gbench")
    if not os.path.isdir(directory):
        return programs
    for name in sorted(os.listdir(directory)):
        if not name.endswith(".json"):
            continue
        with open(os.path.join(directory, name), encoding="utf-8") as f:
            text = f.read()
        try:
            data = json.loads(re.sub(r"-nan\b", "NaN", text))
        except ValueError as error:
            print(f"performance_doc: {name}: {error}; skipped", file=sys.stderr)
            continue
        entries = {}
        for b in data.get("benchmarks", []):
            aggregate = b.get("aggregate_name")
            if b.get("run_type") == "aggregate" and aggregate != "median":
                continue
            parts = b.get("run_name", b["name"]).split("/")
            decorations = ("real_time", "iterations:", "min_time:", "repeats:", "threads:")
            args = tuple(p.split(":")[-1] for p in parts[1:] if not p.startswith(decorations))
            key = (parts[0], args)
            if aggregate == "median" or key not in entries:
                entries[key] = b
        programs[name[:-len(".json")]] = entries
        CONTEXTS[name[:-len(".json")]] = data.get("context", {})
    return programs


# Per program, its run's Google Benchmark context: a program re-run alone (scripts/bench.sh
# --gbench-only NAME) records its own commit and date there (drape_commit, drape_date).
CONTEXTS = {}


def source(doc, program):
    """The line under a program's table: its own run's commit when it was re-run alone."""
    context = CONTEXTS.get(program, {})
    doc.source(program, context.get("drape_commit"), context.get("drape_date"))


def value(gb, program, name, args, field="ns_per_particle"):
    entry = gb.get(program, {}).get((name, tuple(str(a) for a in args)))
    if entry is None:
        return None
    v = entry.get(field)
    if field in ("real_time", "cpu_time") and v is not None:  # to ms
        scale = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}[entry.get("time_unit", "ns")]
        v *= scale
    return None if v is None or (isinstance(v, float) and math.isnan(v)) else v


def body_map_queries(doc, gb):
    p = "bench_body_map_query"
    if p not in gb:
        return
    doc.add("## Body maps at run time", "",
            "`bench_body_map_query`: analytic maps of a 0.3 m sphere and of a 1.7 m figure of 10 "
            "capsules in a 1.8 m window; particles 2 mm in front of the surface, half of them "
            "moving through it: resting (steps up to 0.02 texel, cloth lying on the body), "
            "sliding (0.1–0.5 texel) or stepping (1–2 texels). ns per particle, median of 3; "
            "each cell spans the two shapes, one thread / two where the call is parallel.", "",
            "| query | N = 512 | N = 1024 |", "|---|---|---|")

    def shapes(name, args, threads=None):
        def one(n, t):
            rest = args if t is None else (t,) + args
            return span([value(gb, p, name, (s, n) + rest) for s in (0, 1)], ns)

        cells = []
        for n in (512, 1024):
            cells.append(one(n, None) if threads is None else f"{one(n, 1)} / {one(n, 2)}")
        return " | ".join(cells)

    doc.add(f"| IsInside, cloth-sheet order | {shapes('BM_Inside', (0,))} |",
            f"| IsInside, shuffled | {shapes('BM_Inside', (1,))} |",
            f"| InsideBatch | {shapes('BM_InsideBatch', (), threads=True)} |")
    motions = (("resting", 2), ("sliding", 0), ("stepping", 1))
    for sampling, code in (("nearest", 0), ("bilinear", 1)):
        per_n = [[shapes('BM_Continuous', (code, m)).split(" | ")[k] for _, m in motions]
                 for k in (0, 1)]
        doc.add(f"| Query, {sampling}, resting / sliding / stepping | "
                f"{' / '.join(per_n[0])} | {' / '.join(per_n[1])} |")
    for lanes_count, lanes_name in ((8, "eight AVX2 lanes"), (4, "four SSE2 lanes")):
        for label, m in motions:
            doc.add(f"| CollideBatch, {lanes_name}, {label} | "
                    f"{shapes('BM_CollideBatch', (m, lanes_count), threads=True)} |")
    lengths = (1, 4, 16, 64, 256)
    cells = {label: " / ".join(ns(value(gb, p, "BM_SegmentLength", (n, s))) for n in lengths)
             for label, s in (("nearest", 0), ("bilinear", 1))}
    doc.add("", "One `Query` per horizontal segment of a fixed length at a random depth in the "
            "figure, N = 1024 (the walk's cost against its length), ns for segments of " +
            " / ".join(str(n) for n in lengths) + f" texels: nearest {cells['nearest']}, "
            f"bilinear {cells['bilinear']}.")
    source(doc, p)


def hull_queries(doc, gb):
    p = "bench_hull_query"
    if p not in gb:
        return
    doc.add("## Hull colliders at run time", "",
            "`bench_hull_query`: a tilted ellipsoid hull of 20, 80 or 320 faces (each its own "
            "plane) with its hierarchies and map table; points half uniform in the OBB, half "
            "within 5 mm of the surface. ns per query, one thread, median of 3.", "",
            "| step | 20 faces | 80 faces | 320 faces |", "|---|---|---|---|")
    levels = (0, 1, 2)

    def per_level(name, rest=(), field="ns_per_particle"):
        return " | ".join(ns(value(gb, p, name, (lv,) + rest, field)) for lv in levels)

    obb = value(gb, p, "BM_ObbRejection", ())
    doc.add(f"| OBB rejection (points in 3x the box) | - | {ns(obb)} | - |",
            f"| plane inside test | {per_level('BM_PlaneInside')} |",
            f"| Kirkpatrick inside test (both sides) | {per_level('BM_KirkpatrickInside')} |",
            f"| Kirkpatrick location, one side | {per_level('BM_KirkpatrickLocate')} |")
    tests = " | ".join(mm(value(gb, p, "BM_KirkpatrickLocate", (lv,), "node_tests"))
                       for lv in levels)
    doc.add(f"| node tests per location | {tests} |",
            f"| push-out response, whole narrow phase | {per_level('BM_Response', (0,))} |",
            f"| map-table ray response, whole narrow phase | {per_level('BM_Response', (1,))} |",
            f"| map-table ray alone | {per_level('BM_MapTableRay')} |",
            f"| 2 cm segment near the surface (continuous) | {per_level('BM_Segment')} |")
    doc.add("", "`BM_Scene`: `CollideBatch` of 100 000 particles around a 1.7 m figure of 14 "
            "hulls (80 faces) and 6 joint spheres moving over the step; ns per particle, one "
            "thread / two:", "",
            "| mode | within 3 cm of a surface | uniform around the figure | 5 m away |",
            "|---|---|---|---|")
    for label, mode in (("plane test, push-out (default)", 0), ("map-table ray", 1),
                        ("Kirkpatrick", 2)):
        doc.add(f"| {label} | " + " | ".join(
            pair(value(gb, p, "BM_Scene", (1, mode, d)), value(gb, p, "BM_Scene", (2, mode, d)))
            for d in (0, 1, 2)) + " |")
    source(doc, p)


def cloth(doc, gb, sections):
    p = "bench_cloth_step"
    title = "Simulation level: drape's cloth against Bullet's soft body"
    if p not in gb and title not in sections:
        return
    doc.add("## Cloth step", "")
    if p in gb:
        doc.add("`bench_cloth_step`: one 1/60 s frame of a 10 100-particle skirt on a walking "
                "pair of legs (4 box hulls, 16 joint spheres), 5 Verlet iterations per substep, "
                "continuous collision, friction 0.3; ms per frame, median of 3. 1 worker: the "
                "serial task system; 2 workers: `ThreadPoolTaskSystem(2)`; OpenMP: its team of 2 "
                "with `OMP_WAIT_POLICY=passive`. Bullet's soft body (the peer) steps the same "
                "skirt against the same shapes, one thread; depth: the mean over frames of the "
                "deepest particle inside a collider; worst spring: the largest L / R − 1 over the "
                "timed frames (tethers + strain limit: the engine defaults of "
                "`ClothSolverSettings{}`, off in paper B's); beyond the limit: the stretch springs "
                "longer than 1.1 R after a frame, mean over the timed frames. Lean: without the optional per-step "
                "safety work (`measure_stretch` and `guard_blowups` off: the worst-spring pass, the "
                "per-substep backup and finite check), 1 worker / 2 workers.", "",
                "| setup | 1 worker | 2 workers | speed-up | OpenMP, 2 threads | no stretch "
                "measure | lean 1 / 2 workers | depth mm | worst spring | beyond the limit |",
                "|---|---|---|---|---|---|---|---|---|---|")
        for label, substeps, colliders, engine in (
                ("1 substep, with colliders", 1, 1, 0), ("1 substep, solver alone", 1, 0, 0),
                ("1 substep, with colliders, tethers + strain limit", 1, 1, 1),
                ("1 substep, solver alone, tethers + strain limit", 1, 0, 1)):
            args = (substeps, colliders, engine)
            one = value(gb, p, "BM_ClothStep", (1,) + args + (0, 1, 1), "real_time")
            two = value(gb, p, "BM_ClothStep", (2,) + args + (0, 1, 1), "real_time")
            omp = value(gb, p, "BM_ClothStep", (2,) + args + (1, 1, 1), "real_time")
            no_stretch = value(gb, p, "BM_ClothStep", (1,) + args + (0, 0, 1), "real_time")
            lean = [value(gb, p, "BM_ClothStep", (w,) + args + (0, 0, 0), "real_time")
                    for w in (1, 2)]
            depth = value(gb, p, "BM_ClothStep", (1,) + args + (0, 1, 1), "frame_max_depth_mm")
            stretch = value(gb, p, "BM_ClothStep", (1,) + args + (0, 1, 1), "max_stretch_pct")
            beyond = value(gb, p, "BM_ClothStep", (1,) + args + (0, 1, 1),
                           "overstretched_per_frame")
            up = f"{one / two:.2f}x" if one and two else "-"
            lean_pair = (f"{mm(lean[0], 2)} / {mm(lean[1], 2)} ({lean[0] / lean[1]:.2f}x)"
                         if lean[0] and lean[1] else "-")
            doc.add(f"| drape, {label} | {mm(one, 2)} | {mm(two, 2)} | {up} | {mm(omp, 2)} | "
                    f"{mm(no_stretch, 2)} | {lean_pair} | {mm(depth, 2) if colliders else '-'} | "
                    f"{f'{stretch:.0f} %' if stretch is not None else '-'} | "
                    f"{f'{beyond:.0f}' if beyond is not None else '-'} |")
        for substeps in (1,):
            t = value(gb, p, "BM_BulletSkirt", (substeps,), "real_time")
            depth = value(gb, p, "BM_BulletSkirt", (substeps,), "frame_max_depth_mm")
            doc.add(f"| Bullet btSoftBody, {substeps} substep{'s' if substeps > 1 else ''} | "
                    f"{mm(t, 2)} | - | - | - | - | - | {mm(depth, 2)} | - | - |")
        stages = ("integrate", "springs", "constraints", "collide", "bookkeeping")
        per_workers = []
        for workers in (1, 2):
            args = (workers, 1, 1, 0, 0, 1, 1)
            per_workers.append(", ".join(
                f"{k} {mm(value(gb, p, 'BM_ClothStep', args, f'{k}_ms'), 3)}" for k in stages))
        doc.add("", "By stage (`ClothSolverSettings::measure_stages`; integrate: backup and "
                "input check, root motion, integration, attachments; springs: the 5 passes; "
                "constraints: tethers, skinned limits and the velocities, in one pass with the "
                "positions back from the spring solver; collide: every collider's batch; "
                "bookkeeping: contact count with the blow-up check, stretch measure), ms per "
                "frame, 1 substep with "
                f"colliders: 1 worker {per_workers[0]}; 2 workers {per_workers[1]}.")
        source(doc, p)
    if title in sections:
        doc.add("The same comparison on the walking mannequin, penetration measured against the "
                "exact posed body (from `drape-speed-vs-error`): " + sections[title].lstrip())
        doc.source("speed against error")


def shapes(doc, gb):
    p = "bench_shape_collider"
    if p not in gb:
        return
    cells = []
    for label, dist in (("half the particles within 3 cm of a surface", 0),
                        ("uniform in the scene's box", 1),
                        ("a 100 × 100 sheet slanting through the shapes", 3),
                        ("5 m above everything", 2)):
        one = value(gb, p, "BM_ShapeScene", (1, dist))
        two = value(gb, p, "BM_ShapeScene", (2, dist))
        contact = value(gb, p, "BM_ShapeScene", (1, dist), "contact_fraction")
        cell = f"{mm(one, 0)} ns {label}"
        if two:
            cell += f" ({mm(two, 0)} ns on 2 threads)"
        if contact is not None:
            cell += f", {100 * contact:.0f} % in contact"
        cells.append(cell)
    doc.add("**Engine shapes.** `bench_shape_collider`: `ShapeColliderSet::CollideBatch` of 10 000 particles against "
            "16 spheres, 4 tapered capsules, a floor and 2 boxes moving 1 cm and turning 2° in "
            "the substep, per particle, median of 3: " + "; ".join(cells) + ".")
    source(doc, p)


def body_map_bake(doc, gb):
    p = "bench_body_map_bake"
    if p not in gb:
        return
    doc.add("## Bake: body maps", "",
            "`bench_body_map_bake`: one pose of a UV sphere and of a capsule mannequin, about 5k "
            "and 80k triangles. ms per view (the fastest iteration's render time, median of 3 "
            "repetitions); the CPU rasterizer renders both views in one pass and charges each "
            "half.", "",
            "| mesh | renderer | N = 512 | N = 1024 | N = 2048 |", "|---|---|---|---|---|")
    for mesh_label, mannequin in (("sphere", 0), ("mannequin", 1)):
        for fine in (0, 1):
            for renderer, osmesa in (("CPU", 0), ("OSMesa (llvmpipe)", 1)):
                cells = []
                triangles = None
                for n in (512, 1024, 2048):
                    args = (mannequin, fine, n, osmesa, 1)
                    cells.append(mm(value(gb, p, "BM_BodyMapBake", args, "front_min_ms")))
                    triangles = triangles or value(gb, p, "BM_BodyMapBake", args, "triangles")
                if any(c != "-" for c in cells):
                    count = (f"{triangles:,.0f}".replace(",", " ") if triangles
                             else ("80k" if fine else "5k"))
                    doc.add(f"| {mesh_label} {count} | {renderer} | " + " | ".join(cells) + " |")
    gaps = [(m, value(gb, p, "BM_BodyMapBake", (m, 1, 1024, 0, 3), "gap_min_ms")) for m in (0, 1)]
    if any(g for _, g in gaps):
        doc.add("", "The air-gap fragment pass (`maps.layers` 3) on the 80k-triangle meshes at "
                "N = 1024: " + ", ".join(f"{'mannequin' if m else 'sphere'} {mm(g)} ms"
                                         for m, g in gaps) + ".")
    source(doc, p)


def hull_bake(doc, gb):
    p = "bench_hull_bake"
    if p not in gb:
        return
    doc.add("## Bake: hulls", "",
            "`bench_hull_bake`: one limb-like bone (points on a tapered 25 cm capsule), δ 5 mm. "
            "CPU ms per bone (median of 3; one thread, so CPU time is the figure a loaded machine "
            "disturbs least) and, in brackets, the growth beyond the inflated hull in mm.", "", "| simplification, budget 100 triangles | 50 points | 200 points | "
            "400 points |", "|---|---|---|---|")
    modes = (("edge collapse (default)", 0), ("plane removal", 1), ("none", 2))
    for label, mode in modes:
        cells = []
        for points in (50, 200, 400):
            args = (points, mode, 100, 0)
            t = value(gb, p, "BM_HullBake", args, "cpu_time")
            g = value(gb, p, "BM_HullBake", args, "growth_mm")
            cells.append(f"{mm(t)} ({mm(g, 2)})" if t is not None else "-")
        doc.add(f"| {label} | " + " | ".join(cells) + " |")
    budgets = (16, 25, 50, 100, 200, 400)
    doc.add("", "Growth (mm) and planes against the triangle budget, 400 points:", "",
            "| simplification | " + " | ".join(str(b) for b in budgets) + " |",
            "|---|" + "---|" * len(budgets))
    for label, mode in modes[:2]:
        cells = []
        for b in budgets:
            args = (400, mode, b, 1)
            g = value(gb, p, "BM_HullBake", args, "growth_mm")
            planes = value(gb, p, "BM_HullBake", args, "planes")
            cells.append(f"{mm(g, 2)} ({planes:.0f})" if g is not None and planes else "-")
        doc.add(f"| {label} | " + " | ".join(cells) + " |")
    obb = [(label, value(gb, p, "BM_HullBakeObb", (m,), "obb_ms"),
            value(gb, p, "BM_HullBakeObb", (m,), "obb_cm3"))
           for label, m in (("covariance", 0), ("CGAL optimal", 1))]
    if any(t for _, t, _ in obb):
        doc.add("", "OBB of the 400-point bone: " + "; ".join(
            f"{label} {mm(t, 2)} ms, {mm(v, 1)} cm³" for label, t, v in obb) + ".")
    # Every bone of CesiumMan and the whole bakes: one paragraph (the page stays under 300 lines).
    sentences = []
    bones = value(gb, p, "BM_CesiumManHulls", (), "bones")
    if bones:
        sentences.append(
            f"Every bone of CesiumMan, one thread, CPU time: "
            f"{mm(value(gb, p, 'BM_CesiumManHulls', (), 'cpu_time'))} ms for {bones:.0f} "
            f"hulls (slowest bone {mm(value(gb, p, 'BM_CesiumManHulls', (), 'max_bone_ms'))} "
            f"ms, mean {mm(value(gb, p, 'BM_CesiumManHulls', (), 'mean_tris'), 0)} triangles).")
    whole = [value(gb, p, "BM_WholeBake", (k,), "real_time") for k in range(3)]
    if all(whole):
        hulls = [value(gb, p, "BM_WholeBake", (k,), "hulls") for k in range(3)]
        joints = [value(gb, p, "BM_WholeBake", (k,), "joints") for k in range(3)]
        sentences.append(
            "The whole bake (`BakeCharacter`, default config, wall time on the bake's OpenMP "
            f"team): Animated_Human ({joints[0]:.0f} joints) rescaled to 1.75 m "
            f"{whole[0] / 1000:.2f} s ({hulls[0]:.0f} hulls), as its file gives it (5.3 m tall, "
            f"so more convex pieces under the same max_bloat in metres) {whole[1] / 1000:.2f} s "
            f"({hulls[1]:.0f} hulls); CesiumMan ({joints[2]:.0f} joints) {whole[2] / 1000:.2f} s "
            f"({hulls[2]:.0f} hulls).")
    if sentences:
        doc.add("", " ".join(sentences))
    source(doc, p)


def following_maps(doc, gb, rows):
    """Maps that follow a pose no bake saw: per character (first posed body) the rest pose's maps,
    the maps rendered from the skinned mesh at the rest maps' texel and at 2x and 4x it, and the
    per-bone local maps; then the costs."""
    rendered_label = "rendered from the skinned mesh"
    table = {}
    for r in rows:
        if not r["posed"]:
            continue
        by_kind = table.setdefault(r["base"], {"rendered": []})
        if r["setting"].startswith("the rest pose's maps"):
            by_kind["rest"] = r
        elif r["setting"].startswith("per-bone local maps"):
            by_kind["bones"] = r
        elif r["setting"].startswith(rendered_label):
            by_kind["rendered"].append(r)  # finest texel first, as the sweep measures them
    p = "bench_following_maps"
    if not table and p not in gb:
        return
    costs = ""
    if p in gb:
        render = {(region, t, x, m): value(gb, p, "BM_RenderMaps", (region, t, x, m), "real_time")
                  for region in (0, 1) for t in (1, 2) for x in (1, 4) for m in (0, 1, 2, 3)}
        triangles = {m: value(gb, p, "BM_RenderMaps", (0, 1, 4, m), "triangles")
                     for m in (0, 1, 2, 3)}
        count = lambda v: "–" if v is None else f"{v:,.0f}".replace(",", " ")  # noqa: E731
        ms = lambda v: "–" if v is None else (f"{v:.1f}" if v >= 1.0 else f"{v:.2f}")  # noqa: E731
        costs = (f" `{p}` on the mannequin walking (7 584 triangles): rendering one pose's maps "
                 f"at 1.7 mm texels takes {ms(render[(0, 1, 1, 0)])} / "
                 f"{ms(render[(0, 2, 1, 0)])} ms for the whole body and "
                 f"{ms(render[(1, 1, 1, 0)])} / {ms(render[(1, 2, 1, 0)])} ms for a skirt's "
                 "reach; at 7 mm texels (where the people meet the error targets above) "
                 f"{ms(render[(0, 1, 4, 0)])} / {ms(render[(0, 2, 4, 0)])} ms and "
                 f"{ms(render[(1, 1, 4, 0)])} / {ms(render[(1, 2, 4, 0)])} ms (1 / 2 threads). "
                 f"From the render mesh a default bake stores ({count(triangles[1])} "
                 "triangles, within 1 mm): the whole body at 7 mm "
                 f"{ms(render[(0, 1, 4, 1)])} / {ms(render[(0, 2, 4, 1)])} ms, the skirt's reach "
                 f"{ms(render[(1, 1, 4, 1)])} / {ms(render[(1, 2, 4, 1)])} ms. The mannequin "
                 f"subdivided to {count(triangles[2])} triangles (a dense game character) takes "
                 f"{ms(render[(0, 1, 4, 2)])} / {ms(render[(0, 2, 4, 2)])} ms at 7 mm, from its "
                 f"render mesh ({count(triangles[3])} triangles) {ms(render[(0, 1, 4, 3)])} / "
                 f"{ms(render[(0, 2, 4, 3)])} ms. The "
                 "batch of 10k particles near the body costs "
                 f"{ns(value(gb, p, 'BM_RenderedMapsBatch', (1,)))} / "
                 f"{ns(value(gb, p, 'BM_RenderedMapsBatch', (2,)))} ns per particle on the "
                 f"rendered maps and {ns(value(gb, p, 'BM_BoneMapsBatch', (1,)))} / "
                 f"{ns(value(gb, p, 'BM_BoneMapsBatch', (2,)))} on the bone maps.")
    doc.add("## Maps that follow any pose", "",
            "At each character's first measured pose (a clip time between keys, which no default "
            "bake holds): missed % / penetration p99 mm / ns per particle (1 thread). Rendered: "
            "`BodyMapRenderer`, whole body, from the render mesh a default bake stores (the bind "
            "mesh simplified to within 1 mm; `maps.render_tolerance`), at the rest maps' texel "
            "(N = 1024 over the body) and "
            "at 2x and 4x it; its cells give missed % / penetration p99 mm / ms to render the "
            "pose (1 thread) / texel mm. Bone maps: `BoneMapCollider` at the automatic texel (the "
            "rest pose's size / 600), 3 layers." + costs, "",
            "| character | rest maps (not following) | rendered, rest texel | rendered, 2x | "
            "rendered, 4x | bone maps |",
            "|---|---|---|---|---|---|")
    texel_ms = re.compile(r"\(([0-9.]+) mm texel, whole body: ([0-9.]+) ms per pose")

    def cell(r):
        return "–" if r is None else (f"{100 * r['missed_rate']:.2f} / "
                                      f"{r['penetration_p99_mm']:.1f} / "
                                      f"{ns(r['ns_per_particle_1t'])}")

    def rendered_cell(r):
        if r is None:
            return "–"
        m = texel_ms.search(r["setting"])
        cost = f"{m.group(2)} ms / {m.group(1)} mm" if m else "–"
        return f"{100 * r['missed_rate']:.2f} / {r['penetration_p99_mm']:.1f} / {cost}"

    for character, by_kind in table.items():
        rendered = (by_kind["rendered"] + [None] * 3)[:3]
        cells = ([cell(by_kind.get("rest"))] + [rendered_cell(r) for r in rendered] +
                 [cell(by_kind.get("bones"))])
        doc.add(f"| {character} | " + " | ".join(cells) + " |")
    # A program re-run alone (--gbench-only) names its own commit on a line of its own.
    alone = bool(CONTEXTS.get(p, {}).get("drape_commit"))
    doc.source("speed against error, posed bodies" + (f"; {p}" if costs and not alone else ""))
    if costs and alone:
        source(doc, p)
