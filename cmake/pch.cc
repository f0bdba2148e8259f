// The translation unit that builds the shared precompiled header (CMakeLists.txt,
// TWINSIM_PCH); it has no code of its own.
