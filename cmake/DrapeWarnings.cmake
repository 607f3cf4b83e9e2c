# Warnings as errors on our own code only (third-party headers are included as SYSTEM).
function(drape_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
    -Wno-sign-conversion -Werror)
  # GCC 12 reports false -Wrestrict on std::string concatenation (GCC bug 105329). GCC's only:
  # clang refuses an unknown -W option under -Werror.
  target_compile_options(${target} PRIVATE
    $<$<OR:$<COMPILE_LANG_AND_ID:CXX,GNU>,$<COMPILE_LANG_AND_ID:C,GNU>>:-Wno-restrict>)
  # Determinism: no fused multiply-add contraction, so results do not depend on the compiler's choice.
  target_compile_options(${target} PRIVATE -ffp-contract=off)
  # Without OpenMP its pragmas are comments (the loops run on the calling thread).
  if(NOT DRAPE_OPENMP)
    target_compile_options(${target} PRIVATE -Wno-unknown-pragmas)
  endif()
  if(DRAPE_SANITIZE)
    # Every finding stops the test (halt_on_error), but pointer-overflow stays recoverable so
    # that tests/tools/ubsan_suppressions.txt can name the third-party header clang's check
    # finds it in (a non-recoverable check cannot be suppressed).
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer
      -fno-sanitize-recover=all -fsanitize-recover=pointer-overflow)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
endfunction()
