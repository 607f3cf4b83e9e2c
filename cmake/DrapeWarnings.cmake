# Warnings as errors on our own code only (third-party headers are included as SYSTEM).
function(drape_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
    -Wno-sign-conversion -Werror
    # GCC 12 reports false -Wrestrict on std::string concatenation (GCC bug 105329).
    -Wno-restrict)
  # Determinism: no fused multiply-add contraction, so results do not depend on the compiler's choice.
  target_compile_options(${target} PRIVATE -ffp-contract=off)
  # Without OpenMP its pragmas are comments (the loops run on the calling thread).
  if(NOT DRAPE_OPENMP)
    target_compile_options(${target} PRIVATE -Wno-unknown-pragmas)
  endif()
  if(DRAPE_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer
      -fno-sanitize-recover=all)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
endfunction()
