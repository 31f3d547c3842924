# The Debian package (`cmake --build BUILD --target package`, or tools/scripts/setup.sh package):
# everything `cmake --install` installs, under /usr. Configure with -DCMAKE_INSTALL_PREFIX=/usr
# so that the library directory is Debian's multiarch one and the man page names /usr's data.
# Dependencies come from dpkg-shlibdeps; the shlibs file and the ldconfig trigger from CPack.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME grove)
set(CPACK_PACKAGE_VENDOR grove)
set(CPACK_PACKAGE_CONTACT "grove maintainers <maintainers@users.noreply.h-seed-e84db484.example>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "Rao-Blackwellized particle filters with shared persistent maps (FootSLAM, FastSLAM)")
string(CONCAT CPACK_PACKAGE_DESCRIPTION
    "The grove command (FootSLAM on a hexagon grid, landmark FastSLAM, benchmarks), libgrove "
    "(shared and static) with its C++ and C headers, CMake package and pkg-config file, the "
    "Python module for Debian's python3, and the bundled data under /usr/share/grove.")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_GENERATE_SHLIBS ON)
set(CPACK_DEBIAN_PACKAGE_GENERATE_SHLIBS_POLICY ">=")
# Not libraries, so not found by dpkg-shlibdeps: charts need gnuplot; the Python module needs
# the python3 it was built for and numpy; the static library needs the development packages.
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "gnuplot-nox")
if(GROVE_BUILD_PYTHON AND GROVE_PYTHON_VERSION MATCHES "^([0-9]+)\\.([0-9]+)$")
  math(EXPR grove_next_minor "${CMAKE_MATCH_2} + 1")
  string(APPEND CPACK_DEBIAN_PACKAGE_RECOMMENDS ", python3 (>= ${GROVE_PYTHON_VERSION}~)"
         ", python3 (<< ${CMAKE_MATCH_1}.${grove_next_minor}), python3-numpy")
endif()
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "libtbb-dev, libfmt-dev, zlib1g-dev, libhwy-dev, pkg-config")
if(NOT CMAKE_INSTALL_PREFIX STREQUAL "/usr")
  message(STATUS "grove: packaging needs -DCMAKE_INSTALL_PREFIX=/usr (now ${CMAKE_INSTALL_PREFIX})")
endif()
include(CPack)
