#pragma once
#include <cstdint>
#include <string>

namespace fmpc {

// 64-bit FNV-1a (Fowler, Noll, Vo; http://www.isthe.com/chongo/tech/comp/fnv/): the hash compiled artefacts record
// of their rule file, and the checksum of .fzt files. Detects change and corruption; it is not cryptographic.
std::uint64_t fnv1a64(const void* data, std::size_t size, std::uint64_t seed = 0xcbf29ce484222325ULL);
inline std::uint64_t fnv1a64(const std::string& text) { return fnv1a64(text.data(), text.size()); }

}  // namespace fmpc
