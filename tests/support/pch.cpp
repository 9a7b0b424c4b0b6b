// The precompiled headers of the tests (CMakeLists.txt).
