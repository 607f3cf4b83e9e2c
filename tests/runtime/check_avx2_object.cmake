# cmake -DLIBRARY=<libdrape_runtime.a> -DNM=<nm> -P check_avx2_object.cmake
#
# body_map_collider_avx2.cpp is compiled for AVX2 between target pragmas. A weak (COMDAT)
# definition in its object -- an inline function or template instantiation the SSE2 code may use
# too -- could be the copy the linker keeps, and then the baseline path would run AVX2
# instructions on a CPU without them. So the object may define strong and local symbols only.
execute_process(COMMAND ${NM} -A -C --defined-only ${LIBRARY} OUTPUT_VARIABLE symbols
                RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "${NM} failed on ${LIBRARY}")
endif()
string(REPLACE "\n" ";" lines "${symbols}")
set(found 0)
set(weak "")
foreach(line IN LISTS lines)
  if(line MATCHES "body_map_collider_avx2\\.cpp\\.o:")
    math(EXPR found "${found} + 1")
    # nm -A: "<library>:<member>:<address> <type> <name>"; weak types are W w V v u.
    if(line MATCHES ":[0-9a-f]+ [WwVvu] ")
      string(APPEND weak "\n  ${line}")
    endif()
  endif()
endforeach()
if(found EQUAL 0)
  message(FATAL_ERROR "no symbols of body_map_collider_avx2.cpp.o in ${LIBRARY}")
endif()
if(NOT weak STREQUAL "")
  message(FATAL_ERROR "the AVX2 object defines weak symbols (keep them out of its AVX2 region):${weak}")
endif()
message(STATUS "body_map_collider_avx2.cpp.o: ${found} symbols, none weak")
