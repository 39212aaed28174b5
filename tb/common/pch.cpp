// The one source of fpgacnc_test_pch, the library whose precompiled header (CMakeLists.txt) the
// test executables reuse; it has no code of its own.
