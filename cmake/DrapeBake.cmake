# The bake as a step of an asset build (installed with the drape package; find_package(drape)
# includes it when the install has drape-bake):
#
#   drape_add_bake(TARGET hero INPUT hero.fbx OUTPUT hero.drape
#                  [CONFIG bake.json] [SCENE scene.json] [REPORT hero.json] [PREVIEW dir]
#                  [GLTF hero.glb] [STRICT])
#
# adds a target `hero` (built by default) whose one command bakes INPUT into OUTPUT. drape-bake
# writes a dependency file (--depfile) naming every file it read (the model, its external
# buffers, materials and textures, the config, the scene and its garment meshes), so Ninja and
# Make re-bake exactly when one of them, or drape-bake itself, changes. Relative INPUT, CONFIG
# and SCENE resolve against the calling CMakeLists.txt's directory; relative OUTPUT, REPORT and
# PREVIEW and GLTF against its build directory. GLTF also writes the asset as glTF 2.0 (the
# skinned body with every collider on its joint, to look at). STRICT fails the bake on any
# warning.
#
# DRAPE_BAKE_EXECUTABLE names the drape-bake to run (set by the package).
include_guard(GLOBAL)

# In the caller's scope (a macro): no unparsed argument, and every required one given.
macro(_drape_check_arguments function)
  if(ARG_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "${function}: unknown arguments ${ARG_UNPARSED_ARGUMENTS}")
  endif()
  foreach(_drape_required ${ARGN})
    if(NOT ARG_${_drape_required})
      message(FATAL_ERROR "${function}: ${_drape_required} is required")
    endif()
  endforeach()
endmacro()

function(drape_add_bake)
  cmake_parse_arguments(PARSE_ARGV 0 ARG "STRICT"
                        "TARGET;INPUT;OUTPUT;CONFIG;SCENE;REPORT;PREVIEW;GLTF" "")
  _drape_check_arguments(drape_add_bake TARGET INPUT OUTPUT)
  if(NOT DRAPE_BAKE_EXECUTABLE OR (NOT TARGET "${DRAPE_BAKE_EXECUTABLE}"
                                   AND NOT EXISTS "${DRAPE_BAKE_EXECUTABLE}"))
    message(FATAL_ERROR "drape_add_bake(${ARG_TARGET}): no drape-bake in this drape package "
                        "(DRAPE_BAKE_EXECUTABLE='${DRAPE_BAKE_EXECUTABLE}'; a runtime-only "
                        "install, -DDRAPE_BUILD_BAKE=OFF, has none)")
  endif()
  set(bake "${DRAPE_BAKE_EXECUTABLE}")
  if(TARGET "${DRAPE_BAKE_EXECUTABLE}")
    set(bake "$<TARGET_FILE:${DRAPE_BAKE_EXECUTABLE}>")
  endif()

  get_filename_component(input "${ARG_INPUT}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
  get_filename_component(output "${ARG_OUTPUT}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_BINARY_DIR}")
  set(arguments "${input}" -o "${output}" --depfile "${output}.d")
  set(depends "${input}")
  set(outputs "${output}")
  foreach(option CONFIG SCENE)
    if(ARG_${option})
      get_filename_component(file "${ARG_${option}}" ABSOLUTE BASE_DIR
                             "${CMAKE_CURRENT_SOURCE_DIR}")
      string(TOLOWER "${option}" flag)
      list(APPEND arguments "--${flag}" "${file}")
      list(APPEND depends "${file}")
    endif()
  endforeach()
  if(ARG_REPORT)
    get_filename_component(report "${ARG_REPORT}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_BINARY_DIR}")
    list(APPEND arguments --report "${report}")
    list(APPEND outputs "${report}")
  endif()
  if(ARG_GLTF)
    get_filename_component(gltf "${ARG_GLTF}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_BINARY_DIR}")
    list(APPEND arguments --gltf "${gltf}")
    list(APPEND outputs "${gltf}")
  endif()
  if(ARG_PREVIEW)
    get_filename_component(preview "${ARG_PREVIEW}" ABSOLUTE BASE_DIR
                           "${CMAKE_CURRENT_BINARY_DIR}")
    list(APPEND arguments --preview "${preview}")
  endif()
  if(ARG_STRICT)
    list(APPEND arguments --strict)
  endif()
  list(APPEND depends "${DRAPE_BAKE_EXECUTABLE}")  # a new drape-bake re-bakes
  add_custom_command(OUTPUT ${outputs}
                     COMMAND "${bake}" ${arguments}
                     DEPENDS ${depends}
                     DEPFILE "${output}.d"
                     COMMENT "drape-bake ${ARG_TARGET}: ${ARG_INPUT}"
                     VERBATIM)
  add_custom_target(${ARG_TARGET} ALL DEPENDS ${outputs})
endfunction()

#   drape_add_golden_test(NAME hero.golden INPUT hero.fbx GOLDEN golden/hero.drape
#                         [CONFIG bake.json] [SCENE scene.json] [TOLERANCE tolerance.json])
#
# adds a CTest test that bakes INPUT into the build directory and compares the result with the
# GOLDEN asset by meaning (drape-diff: skeleton, clips, mesh, hull planes, spheres, body-map
# depths): it fails, with drape-diff's summary in the test log, when a difference is beyond the
# TOLERANCE file's limits (drape-diff --help lists the keys; default limits are 0.01 mm).
# DRAPE_DIFF_EXECUTABLE names the drape-diff to run (set by the package).
set(_DRAPE_GOLDEN_SCRIPT "${CMAKE_CURRENT_LIST_DIR}/DrapeGoldenTest.cmake")

function(drape_add_golden_test)
  cmake_parse_arguments(PARSE_ARGV 0 ARG "" "NAME;INPUT;GOLDEN;CONFIG;SCENE;TOLERANCE" "")
  _drape_check_arguments(drape_add_golden_test NAME INPUT GOLDEN)
  foreach(tool BAKE DIFF)
    set(executable "${DRAPE_${tool}_EXECUTABLE}")
    if(NOT executable OR (NOT TARGET "${executable}" AND NOT EXISTS "${executable}"))
      message(FATAL_ERROR "drape_add_golden_test(${ARG_NAME}): DRAPE_${tool}_EXECUTABLE "
                          "('${executable}') is not a drape tool of this package")
    endif()
    if(TARGET "${executable}")
      set(executable "$<TARGET_FILE:${executable}>")
    endif()
    set(${tool} "${executable}")
  endforeach()
  set(definitions -DBAKE=${BAKE} -DDIFF=${DIFF})
  foreach(option INPUT GOLDEN CONFIG SCENE TOLERANCE)
    if(ARG_${option})
      get_filename_component(file "${ARG_${option}}" ABSOLUTE BASE_DIR
                             "${CMAKE_CURRENT_SOURCE_DIR}")
      list(APPEND definitions "-D${option}=${file}")
    endif()
  endforeach()
  string(MAKE_C_IDENTIFIER "${ARG_NAME}" file_name)
  list(APPEND definitions "-DOUTPUT=${CMAKE_CURRENT_BINARY_DIR}/golden_tests/${file_name}.drape")
  add_test(NAME ${ARG_NAME} COMMAND ${CMAKE_COMMAND} ${definitions} -P "${_DRAPE_GOLDEN_SCRIPT}")
endfunction()
