// Assertions that stay on in release builds: they catch programmer errors (a broken
// invariant, a contract violated by the caller), never operating errors, which are
// reported as values. A failed assertion prints where and aborts.
#pragma once

#include <cstdio>
#include <cstdlib>

#define KEEL_TASKING_ASSERT(condition)                                                             \
    do {                                                                                           \
        if (!(condition)) {                                                                        \
            std::fprintf(stderr, "%s:%d: assertion failed: %s\n", __FILE__, __LINE__, #condition); \
            std::abort();                                                                          \
        }                                                                                          \
    } while (false)
