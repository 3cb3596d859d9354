# stb from Debian's libstb-dev: headers in <prefix>/include/stb, implementations in libstb.
# Provides the imported target vcar::stb (used by vcar::io and by its installed config) when stb
# is found; leaves it undefined otherwise (the caller decides whether that is an error).
if(NOT TARGET vcar::stb)
  find_package(PkgConfig QUIET)
  if(PkgConfig_FOUND)
    pkg_check_modules(VCAR_STB QUIET stb)
  endif()
  if(VCAR_STB_FOUND)
    add_library(vcar::stb INTERFACE IMPORTED GLOBAL)
    set_target_properties(vcar::stb PROPERTIES
      INTERFACE_INCLUDE_DIRECTORIES "${VCAR_STB_INCLUDE_DIRS}")
    find_library(VCAR_STB_LIBRARY NAMES stb HINTS ${VCAR_STB_LIBRARY_DIRS})
    if(VCAR_STB_LIBRARY)
      set_property(TARGET vcar::stb PROPERTY INTERFACE_LINK_LIBRARIES "${VCAR_STB_LIBRARY}")
    endif()
  else()
    find_path(VCAR_STB_INCLUDE_DIR stb_image.h PATH_SUFFIXES stb)
    find_library(VCAR_STB_LIBRARY NAMES stb)
    if(VCAR_STB_INCLUDE_DIR AND VCAR_STB_LIBRARY)
      add_library(vcar::stb INTERFACE IMPORTED GLOBAL)
      set_target_properties(vcar::stb PROPERTIES
        INTERFACE_INCLUDE_DIRECTORIES "${VCAR_STB_INCLUDE_DIR}"
        INTERFACE_LINK_LIBRARIES "${VCAR_STB_LIBRARY}")
    endif()
  endif()
endif()
