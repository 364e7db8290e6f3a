// Large allocations on transparent huge pages, and a heap prepared for them (huge_pages.cpp).
#pragma once

#include <cstddef>

namespace vtex::cli {

// Grows the heap by `bytes` now, asks for huge pages on all of it before anything is written
// there, and leaves the next allocations to start in it: a command that allocates its arrays
// from a heap it never trims (vtex build, keepFreedMemory) then faults them in 2 MiB at a time,
// small allocations and the ends of large ones included. glibc's main heap only; otherwise, and
// in sanitizer builds, it does nothing. Only speed depends on it.
void reserveHugePageHeap(std::size_t bytes);

}  // namespace vtex::cli
