// Per-light state of a camera march (renderer.cpp).
#pragma once

#include <cstddef>
#include <new>
#include <vector>

namespace vtex::render::detail {

// Per-light state of a march: on the stack for up to 16 lights (every scene of the tests and
// benchmarks), on the heap beyond, so that every light lights every voxel. Only the lights there
// are get constructed: a span's state is made per camera-ray span, and constructing all sixteen
// (a track is 520 bytes, a light's reflectance kernel more) was 4 % of the bush field's middle
// view. They are default-initialised: their members' own initialisers apply, arrays without
// one (a track's 2 × 32 recorded queries, read only below its count) are left as they are.
template <class T>
class PerLight {
public:
    explicit PerLight(std::size_t n) : mCount(n) {
        if (n > kSmall) {
            mLarge.resize(n);
            mData = mLarge.data();
        } else {
            mData = reinterpret_cast<T*>(mSmall);
            for (std::size_t i = 0; i < n; ++i) new (mData + i) T;
        }
    }
    ~PerLight() {
        if (mLarge.empty())
            for (std::size_t i = 0; i < mCount; ++i) mData[i].~T();
    }
    PerLight(const PerLight&) = delete;
    PerLight& operator=(const PerLight&) = delete;
    T& operator[](std::size_t i) { return mData[i]; }
    const T& operator[](std::size_t i) const { return mData[i]; }

private:
    static constexpr std::size_t kSmall = 16;
    alignas(T) unsigned char mSmall[kSmall * sizeof(T)];
    std::vector<T> mLarge;
    std::size_t mCount = 0;
    T* mData = nullptr;
};

}  // namespace vtex::render::detail
