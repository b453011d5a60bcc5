// The extremes matrix (bench/extremes.hpp): every method on every case, with its invariants —
// finite, energy not above the reference's beyond its noise, and error not above `direct`'s —
// or a documented exception. `bench/extremes` writes the same matrix to docs/benchmarks.md.
#include "bench/extremes.hpp"
#include "gpu_fixture.hpp"

#include <gtest/gtest.h>

#include <cctype>
#include <cstdio>
#include <string>

namespace bounce::test {
namespace {

class Extremes : public ::testing::TestWithParam<std::size_t> {};

TEST_P(Extremes, EveryMethodStaysFiniteAndNoWorseThanDirect) {
    const auto cases = bench::extreme_cases();
    const bench::ExtremeCase& extreme = cases.at(GetParam());
    const bench::ExtremeTruth truth = bench::extreme_truth(extreme, bench::kExtremeReferenceBounces);
    const bench::ExtremeTruth isr_truth = bench::extreme_truth(extreme, 1, false);
    ASSERT_EQ(truth.frame.non_finite_count(), 0u) << extreme.name << ": the reference itself";
    const bench::ExtremeVerdict direct = bench::judge(shared_renderer(), extreme, "direct", truth, isr_truth, 0.0);
    for (const std::string method : {"direct", "vct", "isr", "cssm"}) {
        const bench::ExtremeVerdict verdict =
            method == "direct" ? direct : bench::judge(shared_renderer(), extreme, method, truth, isr_truth, direct.rel_mse);
        std::printf("%-24s %-6s finite %d relMSE %.4f (direct %.4f) mean %.5g (bound %.5g)%s%s\n", extreme.name.c_str(),
                    method.c_str(), verdict.finite, verdict.rel_mse, verdict.direct_rel_mse, verdict.mean,
                    verdict.energy_bound, verdict.exception.empty() ? "" : " exception: ", verdict.exception.c_str());
        EXPECT_TRUE(verdict.finite) << extreme.name << ": " << method << " has non-finite pixels";
        if (!verdict.exception.empty()) continue;
        EXPECT_TRUE(verdict.energy_ok) << extreme.name << ": " << method << " mean " << verdict.mean
                                       << " is above the reference's " << verdict.energy_bound;
        EXPECT_TRUE(verdict.error_ok) << extreme.name << ": " << method << " relMSE " << verdict.rel_mse
                                      << " is worse than direct light alone (" << verdict.direct_rel_mse << ")";
    }
}

std::string case_label(const ::testing::TestParamInfo<std::size_t>& param) {
    std::string label = bench::extreme_cases().at(param.param).name;
    for (char& c : label)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    return label;
}

INSTANTIATE_TEST_SUITE_P(Matrix, Extremes, ::testing::Range<std::size_t>(0, bench::extreme_cases().size()), case_label);

}  // namespace
}  // namespace bounce::test
