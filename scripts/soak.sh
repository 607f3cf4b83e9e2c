#!/usr/bin/env bash
# The soak command (beside the test command, not in it): installs what is missing, builds
# drape-sim, then runs samples/scenes/soak.json (the built-in mannequin walking in a
# 100 000-particle skirt) for 10 000 frames and checks the run:
#   - no frame with a non-finite position or velocity (and drape-sim exits 0);
#   - no growth of memory: the resident set size at the end exceeds the one after the first 100
#     frames by at most 1 % + 8 MiB;
#   - no particle left inside: no frame ends with a particle deeper than 1 mm inside a collider.
# It prints the machine, the time per step over the run (per tenth, mean, p99, max) and the
# memory figures from out/soak/stats.json, and exits non-zero when a check fails.
#
#   SOAK_FRAMES=10000    frames to simulate (the scene plays 10 000)
#   SOAK_THREADS=2       worker threads (drape-sim --threads)
#   SOAK_BUILD_DIR=build the build directory: `build` (the default preset) or any other, which is
#                        configured Release without tests when it has no CMakeCache.txt
#   SOAK_OUT=out/soak    the output directory
#   OMP_WAIT_POLICY      passive unless set (the bake's OpenMP loops; the step runs on the
#                        runtime's thread pool; see docs/SCENES.md, "The soak scene")
set -euo pipefail
cd "$(dirname "$0")/.."
frames=${SOAK_FRAMES:-10000}
threads=${SOAK_THREADS:-2}
build=${SOAK_BUILD_DIR:-build}
out=${SOAK_OUT:-out/soak}
jobs=${DRAPE_JOBS:-2}

scripts/setup.sh
if [ "$build" = build ]; then
  cmake --preset default >/dev/null
elif [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DDRAPE_BUILD_TESTS=OFF >/dev/null
fi
cmake --build "$build" -j "$jobs" --target drape-sim

export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
command=("$build/bin/drape-sim" samples/scenes/soak.json -o "$out" --frames "$frames"
  --threads "$threads")
echo "soak: ${command[*]} (OMP_WAIT_POLICY=$OMP_WAIT_POLICY)"
rm -f "$out/stats.json"  # a failed start must not leave an earlier run's figures to read
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
start=$(date +%s.%N)
status=0
"${command[@]}" || status=$?
end=$(date +%s.%N)
load_after=$(cut -d' ' -f1-3 /proc/loadavg)

python3 - "$out/stats.json" "$status" "$start" "$end" "$frames" "$load_before" "$load_after" \
  "${command[*]}" <<'PY'
import json
import os
import sys

stats_path, status, start, end, frames_wanted = sys.argv[1:6]
load_before, load_after, command = sys.argv[6:9]
status, frames_wanted = int(status), int(frames_wanted)
wall = float(end) - float(start)
MIB = 1024.0 * 1024.0
PENETRATION_LIMIT_MM = 1.0     # a frame may end with no particle deeper than this inside
GROWTH_FRACTION, GROWTH_SLACK = 0.01, 8 * MIB  # allowed RSS growth after frame 100

def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "unknown"

def mem_total_gib():
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemTotal:"):
                    return int(line.split()[1]) / (1024.0 * 1024.0)
    except OSError:
        pass
    return 0.0

def frame_ranges(numbers, most=20):
    # [3, 4, 5, 9] -> "3-5, 9"; the first `most` runs
    parts, i = [], 0
    while i < len(numbers):
        j = i
        while j + 1 < len(numbers) and numbers[j + 1] == numbers[j] + 1:
            j += 1
        parts.append(str(numbers[i]) if i == j else "%d-%d" % (numbers[i], numbers[j]))
        i = j + 1
    return ", ".join(parts[:most]) + (", ..." if len(parts) > most else "")

print()
print("soak: machine: %d CPUs (nproc; %d online), %s, %.1f GiB; load average %s before, %s "
      "after" % (len(os.sched_getaffinity(0)), os.cpu_count() or 0, cpu_model(), mem_total_gib(),
                 load_before, load_after))
print("soak: command: %s" % command)
print("soak: wall time %.1f s (%.1f min)" % (wall, wall / 60.0))
try:
    with open(stats_path) as f:
        stats = json.load(f)
except (OSError, ValueError) as error:
    print("soak: FAILED: no readable %s (%s); drape-sim exited with %d" % (stats_path, error, status))
    sys.exit(1)

t = stats["totals"]
frames = stats["frames"]
methods = [m for m in ("maps", "hulls", "spheres") if stats["methods"][m]]
print("soak: scene: %s, %d particles, %d substeps, %s, %d threads, %d/%d frames (+%d settle)"
      % (stats["scene"], t["particles"], stats["substeps"], "+".join(methods) or "no collision",
         t["threads"], t["frames"], frames_wanted, stats["settle"]["frames"]))
print("soak: step ms: mean %.2f, median %.2f, p99 %.2f, max %.2f; point queries %.2f ms/frame"
      % (t["step_ms_mean"], t["step_ms_median"], t["step_ms_p99"], t["step_ms_max"],
         t["measure_ms_mean"]))
print("soak: step ms per tenth of the run: %s" % " ".join("%.2f" % x for x in t["step_ms_tenths"]))
rss = [f["rss_bytes"] for f in frames]
late_max = max(rss[min(100, len(rss)) - 1:]) if rss else 0
print("soak: memory: peak %.1f MiB (VmHWM); RSS after frame 100 %.1f MiB, at the end %.1f MiB, "
      "growth %+.2f MiB (largest after frame 100: %.1f MiB)"
      % (t["rss_peak_bytes"] / MIB, t["rss_after_100_frames_bytes"] / MIB,
         t["rss_end_bytes"] / MIB, t["rss_growth_bytes"] / MIB, late_max / MIB))
print("soak: contacts %.0f per frame (max %d); max stretch %.3f; %d frames end with a particle "
      "inside (at most %d particles); deepest %.3f mm (frame %d)"
      % (t["contacts_mean"], t["contacts_max"], t["max_stretch"],
         t["frames_with_particles_inside"], t["inside_particles_max"], t["max_penetration_mm"],
         t["max_penetration_frame"]))

failures = []
if status != 0:
    failures.append("drape-sim exited with %d" % status)
if t["frames"] != frames_wanted:
    failures.append("simulated %d of %d frames" % (t["frames"], frames_wanted))
nan = [f["frame"] for f in frames if f["nan"]]
if nan or t["nan_frames"]:
    failures.append("%d frames with NaN: %s" % (len(nan), frame_ranges(nan)))
limit = GROWTH_FRACTION * t["rss_after_100_frames_bytes"] + GROWTH_SLACK
if t["rss_after_100_frames_bytes"] == 0 or t["rss_end_bytes"] == 0:
    failures.append("no resident set size (/proc/self/statm unreadable)")
elif t["rss_growth_bytes"] > limit:
    failures.append("memory grew %.2f MiB after frame 100 (limit %.2f MiB)"
                    % (t["rss_growth_bytes"] / MIB, limit / MIB))
deep = [f["frame"] for f in frames if f["max_penetration_mm"] > PENETRATION_LIMIT_MM]
if deep:
    failures.append("%d frames end with a particle more than %.1f mm inside: %s"
                    % (len(deep), PENETRATION_LIMIT_MM, frame_ranges(deep)))
for failure in failures:
    print("soak: FAILED: %s" % failure)
if failures:
    sys.exit(1)
print("soak: passed: no NaN, memory growth %.2f MiB <= %.2f MiB, no particle more than %.1f mm "
      "inside" % (t["rss_growth_bytes"] / MIB, limit / MIB, PENETRATION_LIMIT_MM))
PY
