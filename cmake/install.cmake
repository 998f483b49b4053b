# `cmake --install build --prefix P`: the program, the role libraries with their public headers,
# the CMake package (find_package(iphong CONFIG)), iphong.pc and the Python package.
include(CMakePackageConfigHelpers)

set(IPHONG_ROLES core reflectance geometry render solve integrate calibrate material near io)
set(IPHONG_ROLE_TARGETS)
foreach(role IN LISTS IPHONG_ROLES)
  set_target_properties(iphong_${role} PROPERTIES EXPORT_NAME ${role})
  list(APPEND IPHONG_ROLE_TARGETS iphong_${role})
endforeach()
# iphong::iphong: every role (iphong_io links the others).
add_library(iphong_all INTERFACE)
set_target_properties(iphong_all PROPERTIES EXPORT_NAME iphong)
target_link_libraries(iphong_all INTERFACE iphong_io)
add_library(iphong::iphong ALIAS iphong_all)

install(TARGETS iphong RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(TARGETS ${IPHONG_ROLE_TARGETS} iphong_all EXPORT iphongTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/iphong)
# Public headers: every role's, not the files named internal (implementation details), except
# solve/internal.h, whose templated helpers the solver's public headers use inline.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/src/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/iphong
  FILES_MATCHING PATTERN "*.h" PATTERN "internal.h" EXCLUDE PATTERN "*_internal.h" EXCLUDE)
install(FILES ${PROJECT_SOURCE_DIR}/src/solve/internal.h
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/iphong/solve)
install(FILES ${PROJECT_BINARY_DIR}/src/generated/core/version.h
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/iphong/core)

set(IPHONG_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/iphong)
install(EXPORT iphongTargets NAMESPACE iphong:: DESTINATION ${IPHONG_CMAKE_DIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/iphongConfig.cmake.in
  ${PROJECT_BINARY_DIR}/iphongConfig.cmake INSTALL_DESTINATION ${IPHONG_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/iphongConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/iphongConfig.cmake ${PROJECT_BINARY_DIR}/iphongConfigVersion.cmake
  DESTINATION ${IPHONG_CMAKE_DIR})

# pkg-config: the role libraries in link order, then what they link (shared, from Debian).
set(IPHONG_PC_LIBS)
foreach(role io near material calibrate solve integrate render geometry reflectance core)
  string(APPEND IPHONG_PC_LIBS " -liphong_${role}")
endforeach()
string(STRIP "${IPHONG_PC_LIBS}" IPHONG_PC_LIBS)
# glog: Ceres's headers check with glog's CHECK macros, so iphong's own objects can call it
# (Ceres's CMake package passes glog on; a .pc file must name it).
set(IPHONG_PC_DEPS "-lceres -lglog -lopencv_imgcodecs -lopencv_imgproc -lopencv_core -pthread")
if(CHOLMOD_LIBRARY)
  string(APPEND IPHONG_PC_DEPS " -lcholmod")
endif()
# Relocatable: the prefix is found from the .pc file's own folder, so `--prefix P` at install
# time is honoured.
file(RELATIVE_PATH IPHONG_PC_UP /p/${CMAKE_INSTALL_LIBDIR}/pkgconfig /p)
configure_file(${PROJECT_SOURCE_DIR}/cmake/iphong.pc.in ${PROJECT_BINARY_DIR}/iphong.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/iphong.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
