#!/usr/bin/env bash
# tests/runtime/check_avx2_object.sh LIBRARY: fails when the AVX2 object of drape_runtime could
# hand AVX2 code to the baseline path.
#
# body_map_collider_avx2.cpp compiles only its own region for AVX2 (target pragmas after every
# #include). A function it defines weakly (COMDAT: inline functions, template instantiations)
# that another object of the library also defines is merged by the linker, which may keep either
# copy. So such a shared function must not contain AVX2-target instructions here (VEX, POPCNT,
# CRC32). Functions only this object defines (its __m256 overloads, when a build does not inline
# them) may, and do. An optimised build inlines nearly everything; the sanitizer build (Debug)
# leaves dozens of weak functions, which is where this check bites.
set -euo pipefail
library=$(realpath "$1")
member=body_map_collider_avx2.cpp.o
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
if ! (cd "$scratch" && ar x "$library" "$member"); then
  echo "FAIL: no $member in $library"
  exit 1
fi
object=$scratch/$member
# Functions with AVX (VEX-encoded) instructions, or POPCNT or CRC32 (which the AVX2 target
# implies), by mangled name.
objdump -d --no-show-raw-insn "$object" |
  awk '/^[0-9a-f]+ <.*>:$/ { name = substr($2, 2, length($2) - 3); next }
       /\tv[a-z0-9]+ |%ymm|\tpopcnt |\tcrc32/ { if (name != "") print name }' | sort -u >"$scratch/avx"
nm --defined-only "$object" | awk '$2 ~ /^[WwVvu]$/ { print $3 }' | sort -u >"$scratch/weak"
nm -A --defined-only "$library" | grep -v ":$member:" | awk '{ print $NF }' | sort -u >"$scratch/others"
if [ ! -s "$scratch/avx" ]; then
  echo "FAIL: $member holds no AVX instruction: the target region did not apply"
  exit 1
fi
shared=$(comm -12 "$scratch/weak" "$scratch/others" | comm -12 - "$scratch/avx")
if [ -n "$shared" ]; then
  echo "FAIL: $member defines, with AVX2-target instructions, weak functions other objects also define:"
  echo "$shared" | c++filt | sed 's/^/  /'
  exit 1
fi
echo "$member: $(wc -l <"$scratch/avx") functions with AVX2-target code, $(wc -l <"$scratch/weak") weak," \
  "$(comm -12 "$scratch/weak" "$scratch/others" | wc -l) of them shared, none of those with AVX2-target code"
