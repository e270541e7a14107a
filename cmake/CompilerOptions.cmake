# One place that gives every regbench target its language level and warnings.
function(regbench_target_options target)
    target_compile_features(${target} PUBLIC cxx_std_17)
    set_target_properties(${target} PROPERTIES CXX_EXTENSIONS OFF POSITION_INDEPENDENT_CODE ON)
    # -Wconversion (kiss-icp's set): implicit narrowing (double -> int, int64 -> int) is a
    # warning. On 2026-12-03 a -fsyntax-only pass over 16 sources (core/*.cpp, gmm/gauss_sum,
    # baselines/cpd, runners/runner, protocols/pair_protocols, datasets/procedural) gave none.
    target_compile_options(${target} PRIVATE -Wall -Wextra -Wconversion)
endfunction()
