// The renderer's memory budget: reservations within it, refusals past it that
// change nothing and say why, and the shrink step that drops what is optional first.
#include <gtest/gtest.h>

#include <thread>
#include <vector>

#include "core/memory_ledger.h"

namespace brdfa {
namespace {

constexpr uint64_t MiB = 1 << 20;

TEST(MemoryLedger, ReservesWithinTheBudgetAndRefusesPastItChangingNothing) {
  MemoryLedger ledger(100 * MiB, "the test budget (100 MiB)");
  ASSERT_TRUE(ledger.reserve(MemoryUse::RenderTargets, 60 * MiB, "view A"));
  ASSERT_TRUE(ledger.reserve(MemoryUse::Assets, 40 * MiB, "the mesh 'm'"));  // exactly full
  auto refused = ledger.reserve(MemoryUse::RenderTargets, 1, "view B");
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().code, ErrorCode::OverBudget);
  const std::string message = refused.error().message;
  EXPECT_NE(message.find("view B needs 0 MiB of render targets"), std::string::npos) << message;
  EXPECT_NE(message.find("the test budget (100 MiB) has 0 MiB left"), std::string::npos) << message;
  const MemoryUsage u = ledger.usage();
  EXPECT_EQ(u.renderTargets, 60 * MiB);
  EXPECT_EQ(u.assets, 40 * MiB);
  EXPECT_EQ(u.total(), 100 * MiB);
}

TEST(MemoryLedger, AnExchangeCountsTheOldShareAsGivenBack) {
  MemoryLedger ledger(100 * MiB, "");
  ASSERT_TRUE(ledger.reserve(MemoryUse::RenderTargets, 70 * MiB, "view"));
  // 70 -> 90 fits because the 70 are given back in the same step; 70 + 90 would not.
  ASSERT_TRUE(ledger.exchange(MemoryUse::RenderTargets, 70 * MiB, 90 * MiB, "view"));
  EXPECT_EQ(ledger.usage().renderTargets, 90 * MiB);
  auto refused = ledger.exchange(MemoryUse::RenderTargets, 90 * MiB, 101 * MiB, "view");
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("the renderer's memory budget (100 MiB) has 100 MiB left"), std::string::npos)
      << refused.error().message;
  EXPECT_EQ(ledger.usage().renderTargets, 90 * MiB) << "a refused exchange keeps the old share";
  // Giving back never fails, even past what is held (it stops at zero).
  ASSERT_TRUE(ledger.exchange(MemoryUse::RenderTargets, 90 * MiB, 0, "view"));
  ledger.release(MemoryUse::RenderTargets, 5 * MiB);
  EXPECT_EQ(ledger.usage().total(), 0u);
}

TEST(MemoryLedger, ShrinkDropsWhatIsOptionalThenTheReservationFits) {
  MemoryLedger ledger(100 * MiB, "");
  MemoryReservation cached(&ledger, MemoryUse::Programs, 0);
  ASSERT_TRUE(ledger.reserve(MemoryUse::Programs, 30 * MiB, "cached programs"));
  cached = MemoryReservation(&ledger, MemoryUse::Programs, 30 * MiB);
  ASSERT_TRUE(ledger.reserve(MemoryUse::RenderTargets, 60 * MiB, "view A"));
  uint64_t asked = 0;
  std::string dropped;
  auto shrink = [&](uint64_t needed) {
    asked = needed;
    cached.reset();  // gives its 30 MiB back
    ledger.noteDropped(30 * MiB, "dropped 1 cached program (30 MiB)");
    return std::string("dropped 1 cached program (30 MiB)");
  };
  ASSERT_TRUE(ledger.reserve(MemoryUse::RenderTargets, 25 * MiB, "view B", shrink, &dropped));
  EXPECT_EQ(asked, 15 * MiB) << "60 + 30 + 25 is 15 MiB past 100";
  EXPECT_EQ(dropped, "dropped 1 cached program (30 MiB)");
  const MemoryUsage u = ledger.usage();
  EXPECT_EQ(u.programs, 0u);
  EXPECT_EQ(u.renderTargets, 85 * MiB);
  EXPECT_EQ(u.drops, 1u);
  EXPECT_EQ(u.droppedBytes, 30 * MiB);
  EXPECT_EQ(u.lastDropped, "dropped 1 cached program (30 MiB)");
}

TEST(MemoryLedger, WhenShrinkingIsNotEnoughTheRefusalSaysSo) {
  MemoryLedger ledger(100 * MiB, "");
  ASSERT_TRUE(ledger.reserve(MemoryUse::RenderTargets, 90 * MiB, "view A"));
  int calls = 0;
  auto refused = ledger.reserve(MemoryUse::RenderTargets, 20 * MiB, "view B", [&](uint64_t) {
    ++calls;
    return std::string();
  });
  ASSERT_FALSE(refused);
  EXPECT_EQ(calls, 1);
  EXPECT_NE(refused.error().message.find("has 10 MiB left after dropping every unused cached program and asset"),
            std::string::npos)
      << refused.error().message;
  EXPECT_EQ(ledger.usage().renderTargets, 90 * MiB);
}

TEST(MemoryLedger, ConcurrentReservationsNeverPassTheBudget) {
  MemoryLedger ledger(64 * MiB, "");
  std::atomic<uint64_t> granted{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t)
    threads.emplace_back([&] {
      for (int i = 0; i < 1000; ++i) {
        if (ledger.reserve(MemoryUse::Transfers, MiB, "upload")) {
          const uint64_t held = ledger.usage().total();
          EXPECT_LE(held, 64 * MiB);
          ++granted;
          ledger.release(MemoryUse::Transfers, MiB);
        }
      }
    });
  for (auto& t : threads) t.join();
  EXPECT_GT(granted.load(), 0u);
  EXPECT_EQ(ledger.usage().total(), 0u);
}

TEST(MemoryLedger, NoBudgetRefusesNothing) {
  MemoryLedger ledger(0, "");
  EXPECT_TRUE(ledger.reserve(MemoryUse::RenderTargets, uint64_t(1) << 50, "a huge view"));
}

}  // namespace
}  // namespace brdfa
