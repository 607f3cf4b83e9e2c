#!/usr/bin/env bash
# tests/runtime/check_lane_objects.sh LIBRARY: fails when an object of drape_runtime compiled for
# AVX2 (the body-map lanes, the hull plane kernels, the spring kernel) could hand its code to
# another path.
#
# lanes_avx2.cpp and plane_kernels_avx2.cpp compile only their own region for AVX2 (target
# pragmas after every #include). A function such an object defines weakly (COMDAT: inline
# functions, template instantiations) that another object of the library also defines is merged
# by the linker, which may keep either copy. So such a shared function must not contain AVX2
# instructions (VEX-encoded, POPCNT, CRC32): the baseline path could receive the AVX2 copy and
# fault on a CPU without it. Functions only this object defines (its __m256 overloads, when a
# build does not inline them) may, and do. An optimised build inlines nearly everything; the
# sanitizer build (Debug) leaves dozens of weak functions, which is where this check bites.
set -euo pipefail
library=$(realpath "$1")
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
status=0
for member in lanes_avx2.cpp.o plane_kernels_avx2.cpp.o spring_kernels_avx2.cpp.o; do
  if ! (cd "$scratch" && ar x "$library" "$member"); then
    echo "FAIL: no $member in $library"
    exit 1
  fi
  object=$scratch/$member
  # Functions with AVX (VEX- or EVEX-encoded) instructions, or POPCNT or CRC32 (which the AVX2
  # target implies), by mangled name.
  objdump -d --no-show-raw-insn "$object" |
    awk '/^[0-9a-f]+ <.*>:$/ { name = substr($2, 2, length($2) - 3); next }
         /\tv[a-z0-9]+ |%ymm|\tpopcnt |\tcrc32/ { if (name != "") print name }' |
    sort -u >"$scratch/avx"
  nm --defined-only "$object" | awk '$2 ~ /^[WwVvu]$/ { print $3 }' | sort -u >"$scratch/weak"
  nm -A --defined-only "$library" | grep -v ":$member:" | awk '{ print $NF }' |
    sort -u >"$scratch/others"
  if [ ! -s "$scratch/avx" ]; then
    echo "FAIL: $member holds no AVX instruction: the target region did not apply"
    exit 1
  fi
  shared=$(comm -12 "$scratch/weak" "$scratch/others" | comm -12 - "$scratch/avx")
  if [ -n "$shared" ]; then
    echo "FAIL: $member defines, with target instructions, weak functions other objects also define:"
    echo "$shared" | c++filt | sed 's/^/  /'
    status=1
  fi
  # EVEX-encoded instructions (first byte 0x62 in 64-bit code) are AVX-512's: none belongs here.
  evex=$(objdump -d "$object" | grep -cP '^\s+[0-9a-f]+:\t62 ' || true)
  if [ "$evex" -ne 0 ]; then
    echo "FAIL: $member holds $evex EVEX-encoded (AVX-512) instructions"
    status=1
  fi
  echo "$member: $(wc -l <"$scratch/avx") functions with target code, $(wc -l <"$scratch/weak") weak," \
    "$(comm -12 "$scratch/weak" "$scratch/others" | wc -l) of them shared," \
    "$(printf '%s' "$shared" | grep -c . || true) of those with target code"
  rm -f "$object"
done
exit $status
