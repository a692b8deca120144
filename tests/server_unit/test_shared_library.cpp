// Two replicas share one data folder: a BRDF saved or deleted through one library is
// seen by the other's next lookup, with no restart.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include "util/atomic_file.h"
#include "storage/brdf_library.h"

namespace brdfa::server {
namespace {

namespace fs = std::filesystem;

const char* kSource =
    "analytic\n::begin parameters\ncolor Kd 1 1 1\n::end parameters\n::begin shader\n"
    "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return Kd / 3.14159265; }\n::end shader\n";

struct TempFolder {
  fs::path path = fs::temp_directory_path() / ("brdfa-shared-" + std::to_string(::getpid()) + "-" +
                                               ::testing::UnitTest::GetInstance()->current_test_info()->name());
  TempFolder() { fs::remove_all(path); }
  ~TempFolder() { fs::remove_all(path); }
};

std::shared_ptr<const BrdfDefinition> parsed(const std::string& text) {
  auto p = parseBrdf(text);
  EXPECT_TRUE(p) << p.error().message;
  return std::make_shared<const BrdfDefinition>(std::move(p.value()));
}

TEST(SharedLibrary, SaveAndDeleteThroughOneAreSeenByTheOther) {
  TempFolder dir;
  BrdfLibrary a, b;
  a.loadUserDir(dir.path.string());
  b.loadUserDir(dir.path.string());
  ASSERT_EQ(b.find("shared_one"), nullptr);

  ASSERT_EQ(a.putUser("shared_one", kSource, parsed(kSource)), BrdfLibrary::PutOutcome::Created);
  auto seen = b.find("shared_one");
  ASSERT_NE(seen, nullptr) << "a save through the other replica is not seen";
  EXPECT_EQ(seen->source, kSource);
  EXPECT_EQ(b.find("shared_one"), seen) << "an unchanged file must keep its entry";

  // A replace, then a file that no longer parses (listed as broken, like at start-up).
  const std::string changed = std::string(kSource) + "# changed\n";
  a.putUser("shared_one", changed, parsed(changed));
  ASSERT_NE(b.find("shared_one"), nullptr);
  EXPECT_EQ(b.find("shared_one")->source, changed);
  ASSERT_TRUE(writeFileAtomically(dir.path / "shared_two.brdf", "analytic\n::begin parameters\nfloat a 0 1\n"));
  EXPECT_TRUE(b.findBroken("shared_two").has_value());

  ASSERT_EQ(a.remove("shared_one"), BrdfLibrary::RemoveOutcome::Removed);
  EXPECT_EQ(b.find("shared_one"), nullptr) << "a delete through the other replica is not seen";
  for (const auto& e : b.list()) EXPECT_NE(e->name, "shared_one");
}

TEST(SharedLibrary, AChangeInTheSameClockTickAsTheLastLookIsStillSeen) {
  // Directory mtimes have the kernel's coarse clock: two changes within one tick leave the same
  // stamp, so a lookup between them must not make the second invisible.
  TempFolder dir;
  BrdfLibrary a, b;
  a.loadUserDir(dir.path.string());
  b.loadUserDir(dir.path.string());
  for (int i = 0; i < 50; ++i) {
    const std::string name = "tick_" + std::to_string(i);
    ASSERT_EQ(a.putUser(name, kSource, parsed(kSource)), BrdfLibrary::PutOutcome::Created);
    ASSERT_NE(b.find(name), nullptr) << name;
  }
}

}  // namespace
}  // namespace brdfa::server
