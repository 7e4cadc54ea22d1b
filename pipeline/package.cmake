# The library's C++ face: `cmake --install build --prefix P` installs P/bin/glaswave, the house's
# static libraries, their headers under P/include/glaswave/ with the umbrella glaswave.hpp, the
# CMake package (find_package(glaswave CONFIG REQUIRED) -> glaswave::glaswave) and share/.
include(CMakePackageConfigHelpers)

# glaswave::glaswave: one target over every library of the house. The umbrella header is staged
# as glaswave/glaswave.hpp, so that code in the tree includes it as installed code does.
get_property(libraries GLOBAL PROPERTY glaswave_libraries)
set(umbrella_stage ${PROJECT_BINARY_DIR}/include/glaswave_umbrella)
file(MAKE_DIRECTORY ${umbrella_stage}/glaswave)
file(CREATE_LINK ${PROJECT_SOURCE_DIR}/pipeline/glaswave.hpp ${umbrella_stage}/glaswave/glaswave.hpp
     SYMBOLIC)
add_library(glaswave_all INTERFACE)
add_library(glaswave::glaswave ALIAS glaswave_all)
set_target_properties(glaswave_all PROPERTIES EXPORT_NAME glaswave)
target_link_libraries(glaswave_all INTERFACE ${libraries})
# The headers are C++20 (std::span, std::numbers): the standard travels with the target, so that a
# consumer without a CMAKE_CXX_STANDARD of its own compiles them (tests/install/consumer).
target_compile_features(glaswave_all INTERFACE cxx_std_20)
target_include_directories(glaswave_all INTERFACE $<BUILD_INTERFACE:${umbrella_stage}>
                                                  $<INSTALL_INTERFACE:include>)

install(TARGETS glaswave RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(TARGETS glaswave_all EXPORT glaswaveTargets)
install(FILES pipeline/glaswave.hpp DESTINATION include/glaswave)

set(package_dir ${CMAKE_INSTALL_LIBDIR}/cmake/glaswave)
install(EXPORT glaswaveTargets NAMESPACE glaswave:: DESTINATION ${package_dir})
configure_package_config_file(pipeline/glaswaveConfig.cmake.in
  ${PROJECT_BINARY_DIR}/glaswaveConfig.cmake INSTALL_DESTINATION ${package_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/glaswaveConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/glaswaveConfig.cmake
              ${PROJECT_BINARY_DIR}/glaswaveConfigVersion.cmake DESTINATION ${package_dir})

# The data: presets, the demo, the plotting scripts, the studies. The installed command finds its
# plotting scripts in P/share/glaswave, next to P/bin.
install(DIRECTORY share/ DESTINATION ${CMAKE_INSTALL_DATADIR}/glaswave
        PATTERN "__pycache__" EXCLUDE)
