// Large allocations on transparent huge pages.
//
// On this project's machines (2-core VMs, THP in "madvise" mode) a page fault costs more than
// the work done on the page: `vtex build` of the 512³ bush spent a quarter of its samples in the
// fault handler and 0.9 s of its 1.8 s in the kernel (perf record -e cpu-clock). Memory the
// kernel backs with 2 MiB pages faults 512 times less often; with glibc's own switch for it
// (GLIBC_TUNABLES=glibc.malloc.hugetlb=1) the build took 0.54–0.63 s and `vtex sample` 0.65–0.9 s
// instead of 1.5–1.8 s. That switch is read at process start, so the vtex executable does the same
// itself: its operator new asks for huge pages (madvise MADV_HUGEPAGE) on the whole 2 MiB pages
// inside every allocation of 2 MiB or more, before anything touches them. Memory still comes from
// malloc and goes back with free; a touched huge page is resident whole, so the resident set can
// grow by at most 2 MiB per such allocation. The libraries and the tests keep the plain
// allocator, and so do sanitizer builds, whose operator new checks new/delete pairs.
#include "huge_pages.h"

#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)

#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <new>

namespace {

constexpr std::uintptr_t kHugePage = std::uintptr_t(2) << 20;
constexpr std::size_t kAdviseFrom = std::size_t(2) << 20;

void* allocate(std::size_t n) {
    void* p = std::malloc(n ? n : 1);
    if (!p) throw std::bad_alloc();
    if (n >= kAdviseFrom) {
        const std::uintptr_t begin = (reinterpret_cast<std::uintptr_t>(p) + kHugePage - 1) & ~(kHugePage - 1);
        const std::uintptr_t end = (reinterpret_cast<std::uintptr_t>(p) + n) & ~(kHugePage - 1);
        // Advice only: a kernel without THP refuses it, and nothing changes.
        if (end > begin) ::madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
    }
    return p;
}

}  // namespace

void* operator new(std::size_t n) { return allocate(n); }
void* operator new[](std::size_t n) { return allocate(n); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
    try {
        return allocate(n);
    } catch (...) {
        return nullptr;
    }
}
void* operator new[](std::size_t n, const std::nothrow_t& t) noexcept { return operator new(n, t); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }

// The advice above misses what vtex build's heap holds outside the middles of its large blocks:
// the 4 KiB pages at each block's ends (glibc writes a chunk header there before the advice
// comes) and every small allocation. Advising the heap itself when it grows, before glibc writes
// to it, is what glibc does with GLIBC_TUNABLES=glibc.malloc.hugetlb=1, a setting read only at
// process start; this does the same once, for the heap growth that one block of `bytes` makes.
// A 256³ bush build took 2,400–2,900 page faults, 470 of them the program's start (vtex
// --version), and 580 with this (perf stat).
#if defined(__GLIBC__)
namespace {
// The block reserveHugePageHeap keeps; volatile, since the compiler may leave a block nobody
// reads unallocated.
void* volatile heapFiller = nullptr;
}  // namespace
#endif

void vtex::cli::reserveHugePageHeap(std::size_t bytes) {
#if defined(__GLIBC__)
    const std::uintptr_t oldBreak = reinterpret_cast<std::uintptr_t>(::sbrk(0));
    void* block = std::malloc(bytes);
    if (!block) return;
    const std::uintptr_t start = reinterpret_cast<std::uintptr_t>(block);
    const std::uintptr_t newBreak = reinterpret_cast<std::uintptr_t>(::sbrk(0));
    const std::uintptr_t begin = (oldBreak + kHugePage - 1) & ~(kHugePage - 1);
    const std::uintptr_t end = newBreak & ~(kHugePage - 1);
    // The block came from the heap's top and the heap grew past it: any other layout (an mmap'd
    // block, a heap that could not grow) is left as it is.
    const bool grown = start < begin && begin < end && start + bytes <= newBreak;
    if (grown) ::madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
    std::free(block);  // back into the top chunk: the heap is never trimmed (keepFreedMemory)
    // The top chunk starts at `block` again, below the advised range: a block that fills it up to
    // `begin` is kept for good (its pages untouched but for its two headers), so that the next
    // allocations start on advised memory (malloc's chunk of n − 8 bytes spans n bytes here,
    // n a multiple of 16, as begin − start is).
    if (grown) heapFiller = std::malloc(begin - start - 8);
#else
    static_cast<void>(bytes);
#endif
}

#else

void vtex::cli::reserveHugePageHeap(std::size_t) {}

#endif
