// The glTF reader's accessor decoding (gltf_reader.cpp): component sizes and reads, and
// GltfDecoder, which checks every bufferView and accessor extent (overflow-safe, bounded by the
// triangle limit) before reading their elements. Internal to ingest.
#pragma once

#include "detail.h"

#include <vtex/core/error.h>

#include <tiny_gltf.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

namespace vtex::ingest::detail {


inline int componentSize(int componentType) {
    switch (componentType) {
        case TINYGLTF_COMPONENT_TYPE_BYTE:
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
        case TINYGLTF_COMPONENT_TYPE_SHORT:
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
        default: return 0;
    }
}

inline int componentCount(int type) {
    switch (type) {
        case TINYGLTF_TYPE_SCALAR: return 1;
        case TINYGLTF_TYPE_VEC2: return 2;
        case TINYGLTF_TYPE_VEC3: return 3;
        case TINYGLTF_TYPE_VEC4: return 4;
        default: return 0;  // matrices: no attribute vtex reads is a matrix
    }
}

inline double readComponent(const unsigned char* p, int componentType, bool normalized) {
    switch (componentType) {
        case TINYGLTF_COMPONENT_TYPE_BYTE: {
            std::int8_t v;
            std::memcpy(&v, p, 1);
            return normalized ? std::max(v / 127.0, -1.0) : v;
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: {
            std::uint8_t v;
            std::memcpy(&v, p, 1);
            return normalized ? v / 255.0 : v;
        }
        case TINYGLTF_COMPONENT_TYPE_SHORT: {
            std::int16_t v;
            std::memcpy(&v, p, 2);
            return normalized ? std::max(v / 32767.0, -1.0) : v;
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
            std::uint16_t v;
            std::memcpy(&v, p, 2);
            return normalized ? v / 65535.0 : v;
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
            std::uint32_t v;
            std::memcpy(&v, p, 4);
            return normalized ? v / 4294967295.0 : v;
        }
        default: {
            float v;
            std::memcpy(&v, p, 4);
            return v;
        }
    }
}

class GltfDecoder {
public:
    GltfDecoder(const tinygltf::Model& model, const std::filesystem::path& file, const IngestOptions& options)
        : mModel(model), mFile(file), mOptions(options) {
        // No accessor vtex reads can usefully hold more elements than three per allowed
        // triangle (plus strips and fans, one more per triangle than that at most).
        mMaxElements = options.maxTriangles * 3 + 2;
    }

    void checkBufferViews() {
        for (std::size_t i = 0; i < mModel.bufferViews.size(); ++i) {
            const auto& view = mModel.bufferViews[i];
            const std::string where = "bufferViews[" + std::to_string(i) + "]";
            if (view.buffer < 0 || std::size_t(view.buffer) >= mModel.buffers.size())
                throw InputError(mFile, "buffer index " + std::to_string(view.buffer) + " out of range", where);
            const std::size_t size = mModel.buffers[std::size_t(view.buffer)].data.size();
            if (view.byteOffset > size || view.byteLength > size - view.byteOffset)
                throw InputError(mFile,
                                 "extends past the end of its buffer (offset " +
                                     std::to_string(view.byteOffset) + " + length " +
                                     std::to_string(view.byteLength) + " > " + std::to_string(size) + ")",
                                 where);
            if (view.byteStride != 0 && (view.byteStride < 4 || view.byteStride > 252 || view.byteStride % 4))
                throw InputError(mFile, "byteStride " + std::to_string(view.byteStride) +
                                            " is not a multiple of 4 in [4, 252]", where);
        }
    }

    // The bytes of bufferView `index`, already checked against its buffer.
    std::string_view viewBytes(int index, const std::string& where) const {
        if (index < 0 || std::size_t(index) >= mModel.bufferViews.size())
            throw InputError(mFile, "bufferView " + std::to_string(index) + " out of range", where);
        const auto& view = mModel.bufferViews[std::size_t(index)];
        const auto& data = mModel.buffers[std::size_t(view.buffer)].data;
        return {reinterpret_cast<const char*>(data.data()) + view.byteOffset, view.byteLength};
    }

    /// Reads accessor `index` as doubles, `components` per element, after checking its type,
    /// component type, alignment and extent; applies sparse substitution.
    std::vector<double> readAccessor(int index, const std::vector<int>& allowedComponents,
                                     bool allowNormalizedOrInteger, std::size_t* countOut,
                                     int* componentsOut) const {
        const std::string where = "accessors[" + std::to_string(index) + "]";
        if (index < 0 || std::size_t(index) >= mModel.accessors.size())
            throw InputError(mFile, "accessor " + std::to_string(index) + " out of range", where);
        const auto& accessor = mModel.accessors[std::size_t(index)];
        const int components = checkedComponents(accessor, allowedComponents, allowNormalizedOrInteger, where);
        std::vector<double> values = accessor.bufferView >= 0
                                         ? readDense(accessor, components, where)
                                         // Without a bufferView the elements are zeros (then the sparse values, if any).
                                         : std::vector<double>(accessor.count * std::size_t(components), 0.0);
        if (accessor.sparse.isSparse) applySparse(accessor, components, values, where + ".sparse");
        *countOut = accessor.count;
        *componentsOut = components;
        return values;
    }

    std::vector<std::uint32_t> readIndices(int index) const {
        const std::string where = "accessors[" + std::to_string(index) + "]";
        if (index >= 0 && std::size_t(index) < mModel.accessors.size()) {
            const auto& accessor = mModel.accessors[std::size_t(index)];
            if (accessor.normalized ||
                (accessor.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                 accessor.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
                 accessor.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
                throw InputError(mFile, "indices must be unsigned, non-normalized integers", where);
        }
        std::size_t count = 0;
        int components = 0;
        const std::vector<double> values = readAccessor(index, {1}, true, &count, &components);
        return std::vector<std::uint32_t>(values.begin(), values.end());
    }

private:
    // The accessor's components per element, after checking its type against `allowed`, its
    // component type, normalisation and count (at least one, at most mMaxElements).
    int checkedComponents(const tinygltf::Accessor& accessor, const std::vector<int>& allowed,
                          bool allowNormalizedOrInteger, const std::string& where) const {
        const int components = componentCount(accessor.type);
        if (std::find(allowed.begin(), allowed.end(), components) == allowed.end())
            throw InputError(mFile, "unexpected accessor type", where);
        if (componentSize(accessor.componentType) == 0)
            throw InputError(mFile, "unknown componentType " + std::to_string(accessor.componentType), where);
        if (!allowNormalizedOrInteger && accessor.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT)
            throw InputError(mFile, "componentType must be FLOAT here", where);
        if (accessor.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT && accessor.normalized)
            throw InputError(mFile, "a FLOAT accessor cannot be normalized", where);
        if (accessor.count == 0) throw InputError(mFile, "count is 0", where);
        if (accessor.count > mMaxElements)
            throw InputError(mFile, "count " + std::to_string(accessor.count) + " exceeds the limit of " +
                                        std::to_string(mMaxElements) + " (see --max-triangles)", where);
        return components;
    }

    // The elements of an accessor with a bufferView, after checking its stride, alignment and
    // extent within the view (overflow-safe).
    std::vector<double> readDense(const tinygltf::Accessor& accessor, int components, const std::string& where) const {
        const int size = componentSize(accessor.componentType);
        const std::size_t elementSize = std::size_t(size) * std::size_t(components);
        const std::size_t count = accessor.count;
        const std::string_view bytes = viewBytes(accessor.bufferView, where);
        const auto& view = mModel.bufferViews[std::size_t(accessor.bufferView)];
        const std::size_t stride = view.byteStride ? view.byteStride : elementSize;
        if (stride < elementSize)
            throw InputError(mFile, "byteStride " + std::to_string(stride) +
                                        " is smaller than the element size " + std::to_string(elementSize), where);
        if ((view.byteOffset % std::size_t(size)) || (accessor.byteOffset % std::size_t(size)) ||
            (stride % std::size_t(size)))
            throw InputError(mFile, "byteOffset or byteStride not aligned to the component size " +
                                        std::to_string(size) + " (misaligned)", where);
        // (count − 1) · stride + elementSize ≤ length − offset, without overflow.
        const std::size_t length = bytes.size();
        if (accessor.byteOffset > length || elementSize > length - accessor.byteOffset ||
            (count - 1) > (length - accessor.byteOffset - elementSize) / stride)
            throw InputError(mFile, std::to_string(count) + " elements of " + std::to_string(elementSize) +
                                        " bytes with stride " + std::to_string(stride) + " at offset " +
                                        std::to_string(accessor.byteOffset) + " run past the end of bufferView " +
                                        std::to_string(accessor.bufferView) + " (" + std::to_string(length) +
                                        " bytes)", where);
        std::vector<double> values(count * std::size_t(components));
        const auto* base = reinterpret_cast<const unsigned char*>(bytes.data()) + accessor.byteOffset;
        for (std::size_t i = 0; i < count; ++i)
            for (int c = 0; c < components; ++c)
                values[i * components + c] =
                    readComponent(base + i * stride + std::size_t(c) * size, accessor.componentType, accessor.normalized);
        return values;
    }

    // Substitutes the accessor's sparse values into `values` (count × components), after checking
    // the sparse count, index type, offsets, extents and that the indices strictly increase.
    void applySparse(const tinygltf::Accessor& accessor, int components, std::vector<double>& values,
                     const std::string& where) const {
        const auto& sparse = accessor.sparse;
        const std::size_t count = accessor.count;
        const int size = componentSize(accessor.componentType);
        const std::size_t elementSize = std::size_t(size) * std::size_t(components);
        if (sparse.count <= 0 || std::size_t(sparse.count) > count)
            throw InputError(mFile, "sparse count " + std::to_string(sparse.count) + " out of range", where);
        const int indexSize = componentSize(sparse.indices.componentType);
        if (sparse.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
            sparse.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
            sparse.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
            throw InputError(mFile, "sparse indices must be unsigned integers", where);
        if (sparse.indices.byteOffset < 0 || sparse.values.byteOffset < 0)
            throw InputError(mFile, "negative byteOffset", where);
        const std::string_view indexBytes = viewBytes(sparse.indices.bufferView, where + ".indices");
        const std::string_view valueBytes = viewBytes(sparse.values.bufferView, where + ".values");
        const std::size_t n = std::size_t(sparse.count);
        const std::size_t indexOffset = std::size_t(sparse.indices.byteOffset);
        const std::size_t valueOffset = std::size_t(sparse.values.byteOffset);
        if (indexOffset > indexBytes.size() || n > (indexBytes.size() - indexOffset) / std::size_t(indexSize))
            throw InputError(mFile, "sparse indices run past the end of their bufferView", where);
        if (valueOffset > valueBytes.size() || n > (valueBytes.size() - valueOffset) / elementSize)
            throw InputError(mFile, "sparse values run past the end of their bufferView", where);
        const auto* indexBase = reinterpret_cast<const unsigned char*>(indexBytes.data()) + indexOffset;
        const auto* valueBase = reinterpret_cast<const unsigned char*>(valueBytes.data()) + valueOffset;
        std::uint64_t previous = 0;
        for (std::size_t k = 0; k < n; ++k) {
            const auto target =
                std::uint64_t(readComponent(indexBase + k * std::size_t(indexSize), sparse.indices.componentType, false));
            if (target >= count || (k > 0 && target <= previous))
                throw InputError(mFile, "sparse index " + std::to_string(target) +
                                            " out of range or not strictly increasing", where);
            previous = target;
            for (int c = 0; c < components; ++c)
                values[target * components + c] = readComponent(valueBase + k * elementSize + std::size_t(c) * size,
                                                                accessor.componentType, accessor.normalized);
        }
    }

    const tinygltf::Model& mModel;
    std::filesystem::path mFile;
    const IngestOptions& mOptions;
    std::uint64_t mMaxElements = 0;
};

}  // namespace vtex::ingest::detail
