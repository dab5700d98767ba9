// libFuzzer target: a farm folder's plan.json (core/farm/farm.h checkPlan, taskCommand) as every farm command reads it:
// types, ranges, JSON pointers in the errors, and piece paths that must stay inside the farm folder. The input is the
// plan's text with "@FARM@" standing for the farm folder (a scratch folder of this process, with pieces/ and frames/),
// so that seeds can name the folder they are in. Only specula::Error may leave; anything else or a crash is a finding.
#include "core/farm/farm.h"
#include "core/util/error.h"
#include "fuzz/fuzz_common.h"

#include <filesystem>

using namespace specula;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const std::string farmDir = [] {
        const std::string d = fuzz::scratchDir() + "/farm";
        std::filesystem::create_directories(d + "/pieces");
        std::filesystem::create_directories(d + "/frames");
        return d;
    }();
    std::string text(reinterpret_cast<const char*>(data), size);
    for (size_t at = 0; (at = text.find("@FARM@", at)) != std::string::npos; at += farmDir.size()) text.replace(at, 6, farmDir);
    fuzz::writeScratch("farm/plan.json", reinterpret_cast<const uint8_t*>(text.data()), text.size());
    try {
        const int tasks = farm::checkPlan(farmDir);
        // The array task's body for the first and the last task (no piece exists, so each gives a full argv).
        (void)farm::taskCommand(farmDir, 0);
        (void)farm::taskCommand(farmDir, tasks - 1);
        (void)farm::taskCommand(farmDir, tasks);  // out of range: an InputError
    } catch (const Error&) {
    }
    return 0;
}
