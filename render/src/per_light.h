// Per-light state of a camera march (renderer.cpp).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <vector>

namespace vtex::render::detail {

// Per-light state of a march: on the stack for up to 16 lights (every scene of the tests and
// benchmarks), on the heap beyond, so that every light lights every voxel.
template <class T>
class PerLight {
public:
    explicit PerLight(std::size_t n) {
        if (n > mSmall.size()) {
            mLarge.resize(n);
            mData = mLarge.data();
        } else {
            mData = mSmall.data();
            std::fill_n(mData, n, T{});  // only the lights there are: a track is 520 bytes
        }
    }
    PerLight(const PerLight&) = delete;
    PerLight& operator=(const PerLight&) = delete;
    T& operator[](std::size_t i) { return mData[i]; }
    const T& operator[](std::size_t i) const { return mData[i]; }

private:
    std::array<T, 16> mSmall;
    std::vector<T> mLarge;
    T* mData = nullptr;
};

}  // namespace vtex::render::detail
