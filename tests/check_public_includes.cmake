# Fails, listing each one, when a file of tools/, engine/bindings/ or tests/api/ includes a header
# that is not public: the build's include paths already refuse them, and this check also reads
# the files a given configuration does not compile (MPI, Python, examples, templates).
#   cmake -DROOT=<source tree> [-DEXEMPT=<folders>] -P check_public_includes.cmake
# Allowed: "grove/..." everywhere, "tools/..." in tools/, "engine/bindings/..." in
# engine/bindings/, "tests/api/..." in tests/api/, and system headers; never a path with "..".
# EXEMPT lists folders (relative to ROOT) not read.
cmake_minimum_required(VERSION 3.25)

set(rooms "tools" "engine/bindings" "tests/api")
set(allowed_tools "grove/" "tools/")
set(allowed_engine/bindings "grove/" "engine/bindings/")
set(allowed_tests/api "grove/" "tests/api/")
# Angle-bracket includes are system headers unless they name one of the repository's folders.
set(first_party "engine/" "alloc/" "concurrency/" "tools/" "tests/" "bench/")

set(failures "")
foreach(room IN LISTS rooms)
  file(GLOB_RECURSE files LIST_DIRECTORIES false RELATIVE ${ROOT}
       ${ROOT}/${room}/*.h ${ROOT}/${room}/*.hpp ${ROOT}/${room}/*.cc ${ROOT}/${room}/*.c
       ${ROOT}/${room}/*.in)
  foreach(file IN LISTS files)
    set(skip FALSE)
    foreach(folder IN LISTS EXEMPT)
      string(FIND "${file}" "${folder}/" at)
      if(at EQUAL 0)
        set(skip TRUE)
      endif()
    endforeach()
    if(skip)
      continue()
    endif()
    file(STRINGS ${ROOT}/${file} lines REGEX "^[ \t]*#[ \t]*include")
    foreach(line IN LISTS lines)
      if(NOT line MATCHES "#[ \t]*include[ \t]*([\"<])([^\">]*)[\">]")
        continue()
      endif()
      set(quote "${CMAKE_MATCH_1}")
      set(path "${CMAKE_MATCH_2}")
      # A quoted include must be allowed; an angle-bracket one only when it names our folders.
      set(checked FALSE)
      if(quote STREQUAL "\"")
        set(checked TRUE)
      endif()
      foreach(prefix IN LISTS first_party)
        string(FIND "${path}" "${prefix}" at)
        if(at EQUAL 0)
          set(checked TRUE)
        endif()
      endforeach()
      set(ok TRUE)
      if(checked)
        set(ok FALSE)
        foreach(prefix IN LISTS allowed_${room})
          string(FIND "${path}" "${prefix}" at)
          if(at EQUAL 0)
            set(ok TRUE)
          endif()
        endforeach()
      endif()
      if(path MATCHES "\\.\\.")
        set(ok FALSE)
      endif()
      if(NOT ok)
        string(APPEND failures "  ${file}: ${line}\n")
      endif()
    endforeach()
  endforeach()
endforeach()

if(failures)
  message(FATAL_ERROR "private headers included where only public ones may be (grove/..., and "
                      "tools/... in tools/, engine/bindings/... in engine/bindings/, tests/api/... "
                      "in tests/api/):\n${failures}")
endif()
message(STATUS "public includes: tools/, engine/bindings/ and tests/api/ include only public headers")
