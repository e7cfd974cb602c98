// hawor/slam/place_index.hpp — keyframes indexed by their binary descriptors, for place
// recognition without a trained vocabulary: multi-index hashing (Norouzi, Punjani & Fleet 2012).
//
// Each 256-bit descriptor (binary_descriptor.hpp) is cut into 16 words of 16 bits; the word
// (chunk c, value v) is a visual word, and the index maps it to the entries (keyframes) whose
// descriptors contain it. Two descriptors fewer than 16 bits apart share at least one word
// (pigeonhole); the same point seen again (20–60 bits apart) shares one with probability
// 1 − (1 − (1 − d/256)^16)^16: 0.99 at d = 20, 0.90 at d = 30, 0.20 at d = 60; two unrelated descriptors with
// about 16 · 2⁻¹⁶. As in a bag of words, words held by more than stopFraction of the entries
// (bare walls, saturated sky: not distinctive) are skipped.
// query(): per entry, the number of query descriptors that share a word with at least one of
// its descriptors (each query descriptor votes once per entry); candidates are the entries with
// at least minVotes votes, best first. The verification (descriptor matching and geometry) is
// the caller's.
// Memory: 16 ints per indexed descriptor, plus the descriptors. Not thread-safe while add() runs.
#pragma once

#include <algorithm>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/slam/binary_descriptor.hpp"

namespace hawor {

struct PlaceCandidate {
  int entry;  ///< the id given to add()
  int votes;
};

class PlaceIndex {
 public:
  static constexpr int kChunks = 16;

  /// stopFraction: words held by more than this fraction of the entries are skipped (once there
  /// are at least 10 entries).
  explicit PlaceIndex(double stopFraction = 0.3) : stopFraction_(stopFraction) {
    if (!(stopFraction > 0.0 && stopFraction <= 1.0)) throw Error("PlaceIndex: stopFraction must be in (0, 1]");
  }

  /// Indexes the descriptors of entry `id` (ids need not be dense; an id may be added once).
  void add(int id, const std::vector<BinaryDescriptor>& descriptors) {
    if (id < 0) throw Error("PlaceIndex: entry ids must be >= 0");
    if (static_cast<std::size_t>(id) < known_.size() && known_[static_cast<std::size_t>(id)]) {
      throw Error("PlaceIndex: entry " + std::to_string(id) + " was added before");
    }
    if (static_cast<std::size_t>(id) >= known_.size()) known_.resize(static_cast<std::size_t>(id) + 1, 0);
    known_[static_cast<std::size_t>(id)] = 1;
    ++entries_;
    for (const BinaryDescriptor& d : descriptors) {
      for (int c = 0; c < kChunks; ++c) {
        std::vector<int>& list = words_[key(d, c)];
        if (list.empty() || list.back() != id) list.push_back(id);  // an entry once per word
      }
    }
  }

  int size() const { return entries_; }

  /// Entries sharing words with `descriptors`, by votes (ties: lower id first); `accept(id)`
  /// filters the entries considered (e.g. old enough, another map segment).
  template <typename Accept>
  std::vector<PlaceCandidate> query(const std::vector<BinaryDescriptor>& descriptors, int minVotes, Accept&& accept) const {
    std::vector<int> votes(known_.size(), 0), stamp(known_.size(), -1);
    const std::size_t stop = entries_ >= 10 ? static_cast<std::size_t>(stopFraction_ * entries_) : known_.size();
    for (std::size_t i = 0; i < descriptors.size(); ++i) {
      for (int c = 0; c < kChunks; ++c) {
        const auto it = words_.find(key(descriptors[i], c));
        if (it == words_.end() || it->second.size() > stop) continue;
        for (int id : it->second) {
          if (stamp[static_cast<std::size_t>(id)] == static_cast<int>(i)) continue;
          stamp[static_cast<std::size_t>(id)] = static_cast<int>(i);
          ++votes[static_cast<std::size_t>(id)];
        }
      }
    }
    std::vector<PlaceCandidate> out;
    for (std::size_t id = 0; id < votes.size(); ++id) {
      if (votes[id] >= minVotes && accept(static_cast<int>(id))) out.push_back({static_cast<int>(id), votes[id]});
    }
    std::sort(out.begin(), out.end(), [](const PlaceCandidate& a, const PlaceCandidate& b) {
      return a.votes != b.votes ? a.votes > b.votes : a.entry < b.entry;
    });
    return out;
  }

 private:
  static std::uint32_t key(const BinaryDescriptor& d, int c) {
    const std::uint64_t w = d.bits[static_cast<std::size_t>(c >> 2)];
    return (static_cast<std::uint32_t>(c) << 16) | static_cast<std::uint32_t>((w >> (16 * (c & 3))) & 0xffffu);
  }

  double stopFraction_;
  int entries_ = 0;
  std::vector<char> known_;
  std::unordered_map<std::uint32_t, std::vector<int>> words_;
};

}  // namespace hawor
