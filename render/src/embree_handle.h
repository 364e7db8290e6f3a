// An Embree device or scene owned by a class whose header does not include Embree's: released
// with its owner, or when the owner's constructor throws half-way (declare the device first, so
// that it goes last). embree_ray.h makes them.
#pragma once

#include <memory>

namespace vtex::render::detail {

using EmbreeHandle = std::unique_ptr<void, void (*)(void*)>;

}  // namespace vtex::render::detail
