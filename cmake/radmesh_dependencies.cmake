# Every dependency, found once. RADMESH_PRIVATE_LIBRARIES: what libradmesh
# links privately (a consumer of the static library needs them too: the
# package config finds them again, see radmeshConfig.cmake.in).
include(GNUInstallDirs)
find_package(CGAL 5.5 REQUIRED)
find_package(embree 3 REQUIRED)
find_package(TBB REQUIRED)
find_package(glm REQUIRED)
find_package(tinyobjloader REQUIRED)
find_package(assimp 5 REQUIRED)
find_package(nlohmann_json 3 REQUIRED)
find_package(CLI11 REQUIRED)
# Clipper (Debian's libpolyclipping-dev, no CMake package): the exact direct
# light's polygon Booleans, in integer arithmetic.
find_path(POLYCLIPPING_INCLUDE_DIR polyclipping/clipper.hpp REQUIRED)
find_library(POLYCLIPPING_LIBRARY polyclipping REQUIRED)

set(RADMESH_VTK_COMPONENTS CommonCore CommonDataModel CommonExecutionModel CommonMisc IOXML IOImage)
if(RADMESH_WITH_RENDERING)
  find_package(X11 REQUIRED)
  list(APPEND RADMESH_VTK_COMPONENTS RenderingCore RenderingOpenGL2 RenderingFreeType
       RenderingAnnotation InteractionStyle ChartsCore ViewsContext2D RenderingContextOpenGL2)
endif()
find_package(VTK 9 REQUIRED COMPONENTS ${RADMESH_VTK_COMPONENTS})

set(RADMESH_PRIVATE_LIBRARIES CGAL::CGAL embree TBB::tbb tinyobjloader::tinyobjloader_double assimp::assimp ${VTK_LIBRARIES}
    ${POLYCLIPPING_LIBRARY})
if(RADMESH_WITH_RENDERING)
  list(APPEND RADMESH_PRIVATE_LIBRARIES X11::X11)
endif()
