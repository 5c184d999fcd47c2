/*
 * The plugin records the OpenMM it was built against and refuses another: OpenMM's
 * platform data differ between versions, so a mismatched kernel would read garbage.
 */
#include "TestSupport.h"
#include "internal/OpenMMVersionCheck.h"
#include <gtest/gtest.h>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;

TEST(OpenMMVersion, BuiltAgainstTheOpenMMThatRuns) {
    loadPlugins();
    EXPECT_EQ(Platform::getOpenMMVersion(), getBuiltAgainstOpenMMVersion());
    checkOpenMMVersion(Platform::getOpenMMVersion());  // no exception
    // The platform plugins are those of the same OpenMM (tests set OPENMM_PLUGIN_DIR to them).
    EXPECT_GE(Platform::getNumPlatforms(), 2) << "the CPU platform plugin was not found";
    EXPECT_NO_THROW(Platform::getPlatformByName("CPU"));
    for (const std::string& failure : Platform::getPluginLoadFailures())
        EXPECT_EQ(std::string::npos, failure.find("CPU")) << failure;
}

TEST(OpenMMVersion, AnotherVersionIsRefusedWithWhatToDo) {
    const std::string message = messageOf([] { checkOpenMMVersion("0.1"); });
    EXPECT_NE(std::string::npos, message.find("built against OpenMM " + getBuiltAgainstOpenMMVersion())) << message;
    EXPECT_NE(std::string::npos, message.find("runs OpenMM 0.1")) << message;
    EXPECT_NE(std::string::npos, message.find("-DOPENMM_DIR")) << message;
}
