#include "core/fsm/types.hpp"

#include <gtest/gtest.h>

#include <initializer_list>
#include <vector>

namespace keel::fsm {
namespace {

template <typename Set>
std::vector<int> members(const Set& set) {
    std::vector<int> ids;
    set.for_each([&](auto id) { ids.push_back(id); });
    return ids;
}

TEST(Capacity, IsStatedOnceAndTheSentinelsLieOutsideIt) {
    EXPECT_GE(kMaxNodes, 256);
    EXPECT_GE(kMaxTasks, 1024);
    EXPECT_EQ(NodeSet::kCapacity, kMaxNodes);
    EXPECT_EQ(TaskSet::kCapacity, kMaxTasks);
    EXPECT_EQ(NodeSet::kWords, 4);
    EXPECT_EQ(TaskSet::kWords, 16);
    EXPECT_GE(kNoNode, kMaxNodes);
    EXPECT_GE(kNoTask, kMaxTasks);
    EXPECT_FALSE(NodeSet{}.contains(kNoNode));
}

// Ids at the edges of the words and of the capacity: 0, 63 | 64, 127 | 128, 255.
TEST(IdSet, HoldsEveryIdUpToTheCapacityAcrossWords) {
    NodeSet set;
    for (NodeId id : std::initializer_list<NodeId>{0, 63, 64, 127, 128, 255}) {
        EXPECT_FALSE(set.contains(id)) << id;
        set.insert(id);
        EXPECT_TRUE(set.contains(id)) << id;
    }
    EXPECT_EQ(set.size(), 6);
    EXPECT_EQ(members(set), (std::vector<int>{0, 63, 64, 127, 128, 255}));
    EXPECT_FALSE(set.contains(62));
    EXPECT_FALSE(set.contains(65));
    EXPECT_FALSE(set.contains(254));
    // Ids beyond the capacity are never members, and erasing one changes nothing.
    EXPECT_FALSE(set.contains(256));
    EXPECT_FALSE(set.contains(kNoNode));
    set.erase(256);
    set.erase(kNoNode);
    EXPECT_EQ(set.size(), 6);
    set.erase(64);
    set.erase(255);
    EXPECT_EQ(members(set), (std::vector<int>{0, 63, 127, 128}));
}

TEST(IdSet, TaskSetsReachTheLastTask) {
    TaskSet set;
    set.insert(0);
    set.insert(kMaxTasks - 1);
    set.insert(512);
    EXPECT_TRUE(set.contains(1023));
    EXPECT_FALSE(set.contains(1024));
    EXPECT_EQ(members(set), (std::vector<int>{0, 512, 1023}));
    EXPECT_EQ(set.used_words(), 16);
    set.erase(1023);
    EXPECT_EQ(set.used_words(), 9);
}

TEST(IdSet, SetAlgebraWorksOnEveryWord) {
    NodeSet a;
    NodeSet b;
    for (NodeId id : std::initializer_list<NodeId>{1, 64, 200}) a.insert(id);
    for (NodeId id : std::initializer_list<NodeId>{64, 130, 255}) b.insert(id);
    EXPECT_EQ(members(a | b), (std::vector<int>{1, 64, 130, 200, 255}));
    EXPECT_EQ(members(a & b), (std::vector<int>{64}));
    EXPECT_EQ(members(a.minus(b)), (std::vector<int>{1, 200}));
    EXPECT_TRUE((a | b).includes(a));
    EXPECT_TRUE((a | b).includes(b));
    EXPECT_FALSE(a.includes(b));
    EXPECT_TRUE(a.includes(NodeSet{}));
    NodeSet same;
    for (NodeId id : std::initializer_list<NodeId>{200, 64, 1}) same.insert(id);
    EXPECT_EQ(a, same);
    same.insert(255);
    EXPECT_NE(a, same);
    EXPECT_TRUE(NodeSet{}.empty());
    EXPECT_FALSE(a.empty());
    EXPECT_TRUE(a.minus(a).empty());
}

// A set remembers how many words it may use; the value is its members alone.
TEST(IdSet, AnEmptiedSetEqualsTheEmptySet) {
    NodeSet set;
    set.insert(200);
    set.erase(200);
    EXPECT_TRUE(set.empty());
    EXPECT_EQ(set.size(), 0);
    EXPECT_EQ(set, NodeSet{});
    EXPECT_EQ(set.used_words(), 0);
    NodeSet low;
    low.insert(3);
    set.insert(3);
    EXPECT_EQ(set, low);
    EXPECT_EQ(low, set);
    EXPECT_EQ(members(set | low), (std::vector<int>{3}));
    EXPECT_TRUE(low.includes(set) && set.includes(low));
}

TEST(IdSet, IntersectsAndUnionInPlace) {
    NodeSet a;
    NodeSet b;
    a.insert(5);
    b.insert(250);
    EXPECT_FALSE(a.intersects(b));
    EXPECT_FALSE(b.intersects(a));
    b.insert(5);
    EXPECT_TRUE(a.intersects(b));
    a |= b;
    EXPECT_EQ(members(a), (std::vector<int>{5, 250}));
    TaskSet tasks;
    tasks |= TaskSet{};
    EXPECT_TRUE(tasks.empty());
    TaskSet last;
    last.insert(1023);
    tasks |= last;
    EXPECT_TRUE(tasks.intersects(last));
    EXPECT_EQ(members(tasks.minus(last)), std::vector<int>{});
}

TEST(IdSet, WordsAreWhatTheCodecCarries) {
    NodeSet set;
    EXPECT_EQ(set.used_words(), 0);
    set.insert(3);
    EXPECT_EQ(set.used_words(), 1);
    EXPECT_EQ(set.word(0), std::uint64_t{1} << 3);
    set.insert(255);
    EXPECT_EQ(set.used_words(), 4);
    EXPECT_EQ(set.word(3), std::uint64_t{1} << 63);
    NodeSet copy;
    for (int i = 0; i < NodeSet::kWords; ++i) copy.set_word(i, set.word(i));
    EXPECT_EQ(copy, set);
}

}  // namespace
}  // namespace keel::fsm
