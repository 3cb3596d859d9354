# CTest: runs `bench_field --quick` and checks its CSV: one row per segmenter x method (oracle,
# and grabcut when GRABCUT is ON) on the forward rig, seed 1 (role tuning), target donut, with
# 3D F1, mIoU and the masks' 2D IoU in [0, 1]; and guards the VCAR rows' 3D F1: each at least
# its value measured on 2026-12-02 (x86-64, AVX-512) minus 0.02, and the default at least the
# paper preset's with the honest oracle's masks. With GrabCut's masks the default is below the
# paper preset here (0.937 against 0.993): issue 47's open failure, not guarded.
#   cmake -DBENCH=<bench_field> -DOUT=<dir> [-DGRABCUT=ON] -P check_field_quick.cmake
if(NOT BENCH OR NOT OUT)
  message(FATAL_ERROR "usage: cmake -DBENCH=<bench_field> -DOUT=<dir> [-DGRABCUT=ON] -P check_field_quick.cmake")
endif()
file(REMOVE_RECURSE "${OUT}")
execute_process(COMMAND "${BENCH}" --quick --out "${OUT}" RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "bench_field --quick failed (${rc})")
endif()
foreach(f field.csv field.json)
  if(NOT EXISTS "${OUT}/${f}")
    message(FATAL_ERROR "missing ${OUT}/${f}")
  endif()
endforeach()
file(STRINGS "${OUT}/field.csv" lines)
list(GET lines 0 header)
if(NOT header MATCHES "^method,variant,rig,preset,seed,.*,target,stage,role,segmenter,mask_iou,mask_none,mask_frames$")
  message(FATAL_ERROR "unexpected CSV header: ${header}")
endif()
set(segmenters oracle)
if(GRABCUT)
  list(APPEND segmenters grabcut)
endif()
list(LENGTH segmenters n_seg)
math(EXPR expected "3 * ${n_seg} + 1")
list(LENGTH lines n)
if(NOT n EQUAL expected)
  message(FATAL_ERROR "expected ${expected} lines (header + 3 methods x ${n_seg} segmenters), got ${n}")
endif()
# CMake's regular expressions have no {n}: the skipped fields spelled out.
set(f "[^,]*,")
set(skip8 "${f}${f}${f}${f}${f}${f}${f}${f}")
set(skip6 "${f}${f}${f}${f}${f}${f}")
foreach(seg ${segmenters})
  foreach(mv "vcar,paper,forward,nvos" "vcar,robust,forward,robust" "naive,full,forward,forward")
    set(found FALSE)
    foreach(line ${lines})
      # columns: method,variant,rig,preset,seed, ..., miou (14th), ..., f1_3d (21st), ..., target,stage,role,segmenter,mask_iou,...
      if(line MATCHES "^${mv},1,${skip8}([^,]*),${skip6}([^,]*),.*,donut,three_objects,tuning,${seg},([^,]*),([^,]*),([^,]*)$")
        foreach(v "${CMAKE_MATCH_1}" "${CMAKE_MATCH_2}" "${CMAKE_MATCH_3}")
          if(v STREQUAL "" OR v LESS 0 OR v GREATER 1)
            message(FATAL_ERROR "row ${mv} / ${seg}: a metric '${v}' not in [0, 1]: ${line}")
          endif()
        endforeach()
        set(found TRUE)
        set(f1 "${CMAKE_MATCH_2}")
        string(REGEX MATCH "^[^,]*,([^,]*)," variant "${line}")
        set(f1_${seg}_${CMAKE_MATCH_1} "${f1}")  # f1_<segmenter>_<variant>: paper, robust, full
        break()
      endif()
    endforeach()
    if(NOT found)
      message(FATAL_ERROR "no row for ${mv} with segmenter ${seg} (seed 1, donut, tuning)")
    endif()
  endforeach()
endforeach()
# The guards (3D F1 measured on 2026-12-02 minus 0.02).
set(floor_oracle_paper 0.835)   # measured 0.855
set(floor_oracle_robust 0.955)  # measured 0.975
set(floor_grabcut_paper 0.973)  # measured 0.993
set(floor_grabcut_robust 0.917) # measured 0.937
foreach(seg ${segmenters})
  foreach(v paper robust)
    if(f1_${seg}_${v} LESS floor_${seg}_${v})
      message(FATAL_ERROR "3D F1 of vcar:${v} with ${seg} masks ${f1_${seg}_${v}} < ${floor_${seg}_${v}} (measured minus 0.02)")
    endif()
  endforeach()
endforeach()
if(f1_oracle_robust LESS f1_oracle_paper)
  message(FATAL_ERROR "the default (${f1_oracle_robust}) below the paper preset (${f1_oracle_paper}) with the oracle's masks")
endif()
message(STATUS "field quick: ${n} lines, every segmenter x method present; 3D F1 oracle paper ${f1_oracle_paper} "
               "robust ${f1_oracle_robust}; grabcut paper ${f1_grabcut_paper} robust ${f1_grabcut_robust}")
