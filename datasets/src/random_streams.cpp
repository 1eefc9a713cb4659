#include <clutterscope/datasets/random_streams.hpp>
#include <vector>

namespace clutterscope::datasets {

std::uint64_t splitmix64(std::uint64_t x) {
  std::uint64_t z = x + 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

std::uint64_t fnv1a64(std::string_view text) {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  for (const char c : text) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 0x100000001b3ULL;
  }
  return hash;
}

std::mt19937_64 derive_rng(std::uint64_t seed, std::uint64_t scene, std::uint64_t task) {
  std::seed_seq sequence{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                         static_cast<std::uint32_t>(scene), static_cast<std::uint32_t>(scene >> 32),
                         static_cast<std::uint32_t>(task)};
  return std::mt19937_64(sequence);
}

std::mt19937_64 item_rng(std::uint64_t seed, const ImageKey& key, const std::string& task) {
  std::uint64_t state = seed;
  const auto absorb = [&state](std::uint64_t value) { state = splitmix64(state ^ value); };
  absorb(fnv1a64(key.split));
  absorb(static_cast<std::uint64_t>(static_cast<std::int64_t>(key.scene_id)));
  absorb(static_cast<std::uint64_t>(static_cast<std::int64_t>(key.im_id)));
  absorb(fnv1a64(task));
  // mt19937_64 has 312 words of state: fill it from a seed sequence of 8 mixed words.
  std::vector<std::uint32_t> words;
  for (int i = 0; i < 4; ++i) {
    state = splitmix64(state);
    words.push_back(static_cast<std::uint32_t>(state));
    words.push_back(static_cast<std::uint32_t>(state >> 32));
  }
  std::seed_seq sequence(words.begin(), words.end());
  return std::mt19937_64(sequence);
}

}  // namespace clutterscope::datasets
