// What every example's main() does around its job: check the argument count, and turn
// twinsim's errors into the command line's exit codes (2: bad input, with its
// "path:line: what is wrong" message; 1: anything else).
#pragma once

#include <cstdio>
#include <exception>

#include "core/error.h"

template <typename Job>
int RunExample(int argc, char** argv, int needed, const char* usage, Job job) {
  if (argc < needed) {
    std::fprintf(stderr, "usage: %s %s\n", argv[0], usage);
    return 2;
  }
  try {
    job();
    return 0;
  } catch (const twinsim::InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
