#pragma once

// The random streams of every command, derived from the user's --seed so that results do not
// depend on threads, shards, resume or the order work is done in. Two derivations exist and
// both are kept bit for bit, since published datasets and result folders depend on them:
// - derive_rng (`generate`, `detect`, `sensor-fit`): per (seed, scene, numbered task), the words
//   of seed, scene and task through std::seed_seq;
// - item_rng (the batch commands: estimate, simulate, ...): per (seed, image, named task),
//   splitmix64 over the seed, the split name, the scene and image ids and the task name.

#include <clutterscope/datasets/scene.hpp>
#include <cstdint>
#include <random>
#include <string>
#include <string_view>

namespace clutterscope::datasets {

// splitmix64's output function applied to x + golden gamma (Steele et al. 2014).
std::uint64_t splitmix64(std::uint64_t x);

// 64-bit FNV-1a of the bytes of `text`.
std::uint64_t fnv1a64(std::string_view text);

// The random stream of one (scene, task) of a run with master seed `seed`: independent of the
// order scenes are generated in.
std::mt19937_64 derive_rng(std::uint64_t seed, std::uint64_t scene, std::uint64_t task);

// A random stream for one (seed, image, task): independent of --jobs, shards and resume.
std::mt19937_64 item_rng(std::uint64_t seed, const ImageKey& key, const std::string& task);

}  // namespace clutterscope::datasets
