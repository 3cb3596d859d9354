# CMake has no float arithmetic: F1 in thousandths ("0.993294" -> 993, "1" -> 1000).
function(thousandths value out)
  string(REGEX MATCH "^([01])(\\.([0-9]*))?$" m "${value}")
  set(frac "${CMAKE_MATCH_3}000")
  string(SUBSTRING "${frac}" 0 3 frac)
  math(EXPR k "${CMAKE_MATCH_1} * 1000 + 1${frac} - 1000")
  set(${out} ${k} PARENT_SCOPE)
endfunction()
