// Compiled into every program of the sanitizer build (cmake/radmesh_sanitizers.cmake):
// the sanitizers' settings, read by their runtimes at start, so that tests, the
// CLI the tests run, and the fuzzers all get them without any environment.

// assimp's PLY importer leaks the element it was reading when a file is
// malformed (inside Assimp::Importer::ReadFile, which radmesh holds by value).
extern "C" const char* __lsan_default_suppressions() { return "leak:libassimp.so\n"; }

// Every report with its stack.
extern "C" const char* __ubsan_default_options() { return "print_stacktrace=1"; }
