# Bailey's FastSLAM simulator in grove_tools, with the bundled example_webmap.txt embedded so that
# `grove fastslam simulate` needs no map file. Included by tools/CMakeLists.txt after grove_tools.
set(GROVE_BAILEY_WEBMAP ${CMAKE_CURRENT_SOURCE_DIR}/data/bailey_webmap/example_webmap.txt)
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${GROVE_BAILEY_WEBMAP})
file(READ ${GROVE_BAILEY_WEBMAP} GROVE_EMBEDDED_BAILEY_WEBMAP)
configure_file(embedded_bailey_webmap.cc.in
  ${CMAKE_CURRENT_BINARY_DIR}/embedded_bailey_webmap.cc @ONLY)
target_sources(grove_tools PRIVATE
  fastslam_simulator.cc
  ${CMAKE_CURRENT_BINARY_DIR}/embedded_bailey_webmap.cc
)
