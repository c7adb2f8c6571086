# Compiler flags shared by every target of the project (not exported to users).
add_library(deform_warnings INTERFACE)
target_compile_options(deform_warnings INTERFACE
  $<$<CXX_COMPILER_ID:GNU,Clang>:-Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion>
  # GCC 12 reports std::string concatenation at -O3 as overlapping memcpy (GCC bug 105651, a false positive).
  $<$<CXX_COMPILER_ID:GNU>:-Wno-restrict>)

if(DEFORM_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
endif()
