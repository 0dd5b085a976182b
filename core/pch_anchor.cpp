// A target that only compiles a precompiled header needs one source file
// (posefuse_add_precompiled_headers, CMakeLists.txt).
