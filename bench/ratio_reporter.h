// One ratio reporter for the benches: a console reporter that also keeps each benchmark's median CPU time (ns),
// so that a bench can print "A / B" ratios after the run (bench_filtered_ggx, bench_graph, bench_ltc).
#pragma once

#include <benchmark/benchmark.h>

#include <cstdio>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace specula::bench {

class RatioReporter : public benchmark::ConsoleReporter {
public:
    std::map<std::string, double> medianNs;     // key: function name, plus "/args" when the benchmark has any
    std::map<std::string, std::string> label;   // the benchmark's SetLabel()
    void ReportRuns(const std::vector<Run>& runs) override {
        for (auto& r : runs)
            if (r.aggregate_name == "median") {
                std::string key = r.run_name.function_name;
                if (!r.run_name.args.empty()) key += "/" + r.run_name.args;
                medianNs[key] = r.GetAdjustedCPUTime();
                label[key] = r.report_label;
            }
        ConsoleReporter::ReportRuns(runs);
    }
    bool has(const std::string& key) const { return medianNs.count(key) != 0; }
};

// A bench's main: runs the benchmarks of the command line through a RatioReporter, then hands it to printRatios.
inline int runWithRatios(int argc, char** argv, const std::function<void(RatioReporter&)>& printRatios) {
    benchmark::Initialize(&argc, argv);
    RatioReporter rep;
    benchmark::RunSpecifiedBenchmarks(&rep);
    printRatios(rep);
    benchmark::Shutdown();
    return 0;
}

}  // namespace specula::bench
