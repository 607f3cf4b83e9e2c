#!/usr/bin/env bash
# tests/runtime/check_lane_objects.sh LIBRARY: fails when an object of drape_runtime compiled for a
# wider instruction set than the baseline (the body-map lanes in AVX2, and in AVX2 with AVX-512)
# could hand its code to another path, or when the AVX-512 one uses 512-bit registers.
#
# lanes_avx2.cpp and lanes_avx512.cpp compile only their own region for
# their target (target pragmas after every #include). A function such an object defines weakly
# (COMDAT: inline functions, template instantiations) that another object of the library also
# defines is merged by the linker, which may keep either copy. So such a shared function must not
# contain target instructions here (VEX or EVEX, POPCNT, CRC32): neither the baseline path nor
# the AVX2 one may receive the AVX-512 copy. Functions only this object defines (its __m256
# overloads, when a build does not inline them) may, and do. An optimised build inlines nearly
# everything; the sanitizer build (Debug) leaves dozens of weak functions, which is where this
# check bites.
#
# The AVX-512 object must use no zmm register: its point is AVX-512VL's 32 registers on 256-bit
# vectors, and 512-bit instructions lower the clock of some Intel CPUs.
set -euo pipefail
library=$(realpath "$1")
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
status=0
for member in lanes_avx2.cpp.o lanes_avx512.cpp.o; do
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
  # EVEX-encoded instructions (first byte 0x62 in 64-bit code) are AVX-512's: the AVX-512 object
  # must hold some (else its target did not apply), the AVX2 one none. Register pressure, and so
  # the use of ymm16-31, depends on optimisation (none at -O0): reported, not required.
  evex=$(objdump -d "$object" | grep -cP '^\s+[0-9a-f]+:\t62 ' || true)
  high=$(objdump -d --no-show-raw-insn "$object" | grep -cE '%[xy]mm(1[6-9]|2[0-9]|3[01])\b' || true)
  wide=$(objdump -d --no-show-raw-insn "$object" | grep -c '%zmm' || true)
  if [ "$member" = lanes_avx512.cpp.o ]; then
    if [ "$evex" -eq 0 ]; then
      echo "FAIL: $member holds no EVEX-encoded instruction: the AVX-512 target did not apply"
      status=1
    fi
    if [ "$wide" -ne 0 ]; then
      echo "FAIL: $member has $wide instructions on zmm registers (512-bit):"
      objdump -d --no-show-raw-insn "$object" | grep '%zmm' | head -5 | sed 's/^/  /'
      status=1
    fi
  elif [ "$evex" -ne 0 ]; then
    echo "FAIL: $member holds $evex EVEX-encoded (AVX-512) instructions"
    status=1
  fi
  extra=", $evex EVEX-encoded instructions, $high on ymm16-31, $wide on zmm"
  echo "$member: $(wc -l <"$scratch/avx") functions with target code, $(wc -l <"$scratch/weak") weak," \
    "$(comm -12 "$scratch/weak" "$scratch/others" | wc -l) of them shared," \
    "$(printf '%s' "$shared" | grep -c . || true) of those with target code$extra"
  rm -f "$object"
done
exit $status
