# cmake --install build --prefix P installs libradmesh, its public headers
# (P/include/radmesh: #include <radmesh/radmesh.h>), the radmesh program and a CMake package:
# find_package(radmesh) gives radmesh::radmesh.
include(CMakePackageConfigHelpers)

install(TARGETS radmesh_lib EXPORT radmeshTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(TARGETS radmesh RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY include/radmesh DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(FILES ${PROJECT_BINARY_DIR}/generated/radmesh/version.h DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/radmesh)

set(config_dir ${CMAKE_INSTALL_LIBDIR}/cmake/radmesh)
install(EXPORT radmeshTargets NAMESPACE radmesh:: DESTINATION ${config_dir})
configure_package_config_file(cmake/radmeshConfig.cmake.in ${PROJECT_BINARY_DIR}/radmeshConfig.cmake
                              INSTALL_DESTINATION ${config_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/radmeshConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/radmeshConfig.cmake ${PROJECT_BINARY_DIR}/radmeshConfigVersion.cmake
        DESTINATION ${config_dir})
