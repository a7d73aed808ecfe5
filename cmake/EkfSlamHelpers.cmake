# Small helpers so that each component's CMakeLists.txt stays a list of
# targets, not a page of boilerplate.

# ekf_slam_add_gtest(<name> SOURCES <files...> LIBS <targets...>)
# A gtest run by `catkin_make run_tests` (and so by `make test`). Tests (and
# only tests) know the source tree: EKF_SLAM_SOURCE_DIR, for the worlds and
# the datasets beside it. Installed programs find their data through their
# own location (ekf_slam_program_dir below) or the package's share folder.
function(ekf_slam_add_gtest name)
  cmake_parse_arguments(ARG "" "TIMEOUT" "SOURCES;LIBS" ${ARGN})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 300)
  endif()
  if(CATKIN_ENABLE_TESTING)
    catkin_add_gtest(${name} ${ARG_SOURCES} TIMEOUT ${ARG_TIMEOUT})
    if(TARGET ${name})
      target_link_libraries(${name} ${ARG_LIBS} gtest_main)
      target_compile_definitions(${name} PRIVATE EKF_SLAM_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
    endif()
  endif()
endfunction()

# ekf_slam_add_benchmark(<name> SOURCES <files...> LIBS <targets...>)
# A Google Benchmark executable, built only with -DEKF_SLAM_BUILD_BENCH=ON
# (`make bench`). Output lands in devel/lib/ekf_slam/bench/.
function(ekf_slam_add_benchmark name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBS" ${ARGN})
  if(EKF_SLAM_BUILD_BENCH)
    find_package(benchmark REQUIRED)
    add_executable(${name} ${ARG_SOURCES})
    target_link_libraries(${name} ${ARG_LIBS} benchmark::benchmark)
    set_target_properties(${name} PROPERTIES
      RUNTIME_OUTPUT_DIRECTORY ${CATKIN_DEVEL_PREFIX}/lib/${PROJECT_NAME}/bench)
  endif()
endfunction()

# ekf_slam_add_rostest(<file.test> [DEPENDENCIES <targets...>])
function(ekf_slam_add_rostest file)
  cmake_parse_arguments(ARG "" "" "DEPENDENCIES" ${ARGN})
  if(CATKIN_ENABLE_TESTING)
    find_package(rostest REQUIRED)
    add_rostest(${file} DEPENDENCIES ${ARG_DEPENDENCIES})
  endif()
endfunction()

# ekf_slam_add_fuzzer(<name> SOURCES <files...> LIBS <targets...> CORPUS <dir>)
# A libFuzzer target, built only with -DEKF_SLAM_FUZZ=ON (`make fuzz`); the
# libraries it links are instrumented by the same option. Every fuzzer is a
# dependency of the target `ekf_slam_fuzzers`, and its seed corpus (a folder
# of the source tree) is listed in devel/lib/ekf_slam/fuzz/fuzzers.txt, one
# "<name> <corpus>" line each, for tools/ci/run_fuzzers.sh.
function(ekf_slam_add_fuzzer name)
  cmake_parse_arguments(ARG "" "CORPUS" "SOURCES;LIBS" ${ARGN})
  if(NOT EKF_SLAM_FUZZ)
    return()
  endif()
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} ${ARG_LIBS})
  target_link_options(${name} PRIVATE -fsanitize=fuzzer)
  set(fuzz_dir ${CATKIN_DEVEL_PREFIX}/lib/${PROJECT_NAME}/fuzz)
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${fuzz_dir})
  if(NOT TARGET ekf_slam_fuzzers)
    add_custom_target(ekf_slam_fuzzers)
    file(WRITE ${fuzz_dir}/fuzzers.txt "")
  endif()
  add_dependencies(ekf_slam_fuzzers ${name})
  file(APPEND ${fuzz_dir}/fuzzers.txt "${name} ${ARG_CORPUS}\n")
endfunction()

# ekf_slam_add_program_script(<file>)
# A script a program runs as a child (for example the offline runner's
# plotting script): copied into the devel space's program folder
# (devel/lib/ekf_slam) at configure time and installed into the install
# space's, so that the program finds it beside itself in both, and `rosrun
# ekf_slam <script>` works too.
function(ekf_slam_add_program_script file)
  get_filename_component(name ${file} NAME)
  configure_file(${file} ${CATKIN_DEVEL_PREFIX}/${CATKIN_PACKAGE_BIN_DESTINATION}/${name} COPYONLY)
  install(PROGRAMS ${file} DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
endfunction()



# ekf_slam_add_program_data(<file>)
# A data file a program reads from its own folder (for example the offline
# runner's presets): copied and installed as ekf_slam_add_program_script
# does, without the executable bit.
function(ekf_slam_add_program_data file)
  get_filename_component(name ${file} NAME)
  configure_file(${file} ${CATKIN_DEVEL_PREFIX}/${CATKIN_PACKAGE_BIN_DESTINATION}/${name} COPYONLY)
  install(FILES ${file} DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
endfunction()
