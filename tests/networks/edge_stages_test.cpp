// The fused DGCNN edge stages (networks/layers/edge_stages.hpp) against the LibTorch composition they
// replace in training. Expected values come from EdgeStagesReference: torch::mm, then
// torch::batch_norm with training statistics (which updates the running statistics), relu_,
// max over the k neighbours with indices, and torch::cat, differentiated by LibTorch's autograd;
// it is the code DgcnnImpl ran in training before the fused Function.
#include "networks/layers/edge_stages.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <string>
#include <vector>

#include "networks/layers/layers.hpp"

namespace regbench::networks {
namespace {

/// max |a - b| <= rel * max |b| (+ a floor for all-zero tensors).
void ExpectClose(const torch::Tensor& a, const torch::Tensor& b, double rel,
                 const std::string& what) {
    ASSERT_TRUE(a.defined()) << what;
    ASSERT_TRUE(b.defined()) << what;
    ASSERT_EQ(a.sizes(), b.sizes()) << what;
    const double scale = b.abs().max().item<double>();
    const double diff = (a - b).abs().max().item<double>();
    EXPECT_LE(diff, rel * scale + 1e-30)
        << what << ": max |diff| " << diff << ", max |ref| " << scale;
}

/// Random stage parameters for channel widths c0 -> c1 -> ..., leaves that require gradients,
/// and running statistics away from their initial values.
std::vector<EdgeStage> RandomStages(const std::vector<int64_t>& widths, torch::Dtype dtype) {
    std::vector<EdgeStage> stages;
    for (size_t s = 0; s + 1 < widths.size(); ++s) {
        const int64_t in = widths[s], out = widths[s + 1];
        EdgeStage st;
        st.weight =
            (torch::randn({out, in}, dtype) / std::sqrt(static_cast<double>(in))).requires_grad_();
        st.bn_weight = (1 + 0.3 * torch::randn({out}, dtype)).requires_grad_();
        st.bn_bias = (0.2 * torch::randn({out}, dtype)).requires_grad_();
        st.running_mean = 0.1 * torch::randn({out}, dtype);
        st.running_var = 1 + torch::rand({out}, dtype);
        st.num_batches_tracked = torch::tensor(3, torch::kLong);
        st.momentum = 0.1;
        st.eps = 1e-5;
        stages.push_back(st);
    }
    return stages;
}

/// An independent copy (own leaves, own running statistics).
std::vector<EdgeStage> Copy(const std::vector<EdgeStage>& stages) {
    std::vector<EdgeStage> out = stages;
    for (EdgeStage& s : out) {
        s.weight = s.weight.detach().clone().requires_grad_();
        s.bn_weight = s.bn_weight.detach().clone().requires_grad_();
        s.bn_bias = s.bn_bias.detach().clone().requires_grad_();
        s.running_mean = s.running_mean.clone();
        s.running_var = s.running_var.clone();
        s.num_batches_tracked = s.num_batches_tracked.clone();
    }
    return out;
}

/// Runs both on `rows`, backpropagates the same upstream gradient, compares everything.
void CompareWithReference(const torch::Tensor& rows_in, const std::vector<int64_t>& widths,
                          int64_t k, double rel, int calls = 1) {
    const auto dtype = rows_in.scalar_type();
    const std::vector<EdgeStage> ref = RandomStages(widths, dtype);
    const std::vector<EdgeStage> fused = Copy(ref);
    const torch::Tensor rows_ref = rows_in.clone().requires_grad_();
    const torch::Tensor rows_fused = rows_in.clone().requires_grad_();
    for (int call = 0; call < calls; ++call) {
        const torch::Tensor out_ref = EdgeStagesReference(rows_ref, ref, k);
        const torch::Tensor out_fused = EdgeStagesFused(rows_fused, fused, k);
        ExpectClose(out_fused, out_ref, rel, "output");
        const torch::Tensor upstream = torch::randn(out_ref.sizes(), out_ref.options());
        (out_ref * upstream).sum().backward();
        (out_fused * upstream).sum().backward();
    }
    ExpectClose(rows_fused.grad(), rows_ref.grad(), rel, "d rows");
    for (size_t s = 0; s < ref.size(); ++s) {
        const std::string st = "stage " + std::to_string(s + 1) + ": ";
        ExpectClose(fused[s].weight.grad(), ref[s].weight.grad(), rel, st + "d weight");
        ExpectClose(fused[s].bn_weight.grad(), ref[s].bn_weight.grad(), rel, st + "d bn weight");
        ExpectClose(fused[s].bn_bias.grad(), ref[s].bn_bias.grad(), rel, st + "d bn bias");
        ExpectClose(fused[s].running_mean, ref[s].running_mean, rel, st + "running mean");
        ExpectClose(fused[s].running_var, ref[s].running_var, rel, st + "running var");
        EXPECT_EQ(fused[s].num_batches_tracked.item<int64_t>(), 3 + calls) << st;
        EXPECT_EQ(ref[s].num_batches_tracked.item<int64_t>(), 3 + calls) << st;
    }
}

// 300 points: two full work chunks of 128 points and a partial one.
TEST(EdgeStages, FusedEqualsTheLibTorchCompositionInDouble) {
    torch::manual_seed(1);
    const int64_t points = 300, k = 5;
    const torch::Tensor rows = torch::randn({points * k, 6}, torch::kDouble);
    CompareWithReference(rows, {6, 16, 16, 32, 64}, k, 1e-10);
}

TEST(EdgeStages, OneAndTwoStagesAndRepeatedCallsInDouble) {
    torch::manual_seed(2);
    const int64_t k = 4;
    CompareWithReference(torch::randn({7 * k, 6}, torch::kDouble), {6, 8}, k, 1e-10);
    CompareWithReference(torch::randn({130 * k, 6}, torch::kDouble), {6, 12, 24}, k, 1e-10, 2);
}

/// Relative error in the Frobenius norm.
double RelError(const torch::Tensor& a, const torch::Tensor& truth) {
    return (a.to(torch::kDouble) - truth).norm().item<double>() / truth.norm().item<double>();
}

// In float both implementations round; the truth is the reference composition in double on the
// same (float-representable) inputs. The fused Function's error must be of the order of the
// LibTorch composition's own float error.
TEST(EdgeStages, FusedFloatErrorIsThatOfTheLibTorchComposition) {
    torch::manual_seed(3);
    const int64_t points = 200, k = 20;
    // Features offset from zero, as edge features [x_j - x_i, x_i] of an uncentred cloud are.
    const torch::Tensor rows = torch::randn({points * k, 6}) + 3.0;
    const std::vector<EdgeStage> ref = RandomStages({6, 64, 64, 128, 256}, torch::kFloat);
    const std::vector<EdgeStage> fused = Copy(ref);
    std::vector<EdgeStage> truth = Copy(ref);
    for (EdgeStage& s : truth) {
        for (torch::Tensor* t : {&s.weight, &s.bn_weight, &s.bn_bias}) {
            *t = t->detach().to(torch::kDouble).requires_grad_();
        }
        s.running_mean = s.running_mean.to(torch::kDouble);
        s.running_var = s.running_var.to(torch::kDouble);
    }
    const torch::Tensor rows_ref = rows.clone().requires_grad_();
    const torch::Tensor rows_fused = rows.clone().requires_grad_();
    const torch::Tensor rows_truth = rows.to(torch::kDouble).requires_grad_();
    const torch::Tensor out_ref = EdgeStagesReference(rows_ref, ref, k);
    const torch::Tensor out_fused = EdgeStagesFused(rows_fused, fused, k);
    const torch::Tensor out_truth = EdgeStagesReference(rows_truth, truth, k);
    const torch::Tensor upstream = torch::randn(out_ref.sizes());
    (out_ref * upstream).sum().backward();
    (out_fused * upstream).sum().backward();
    (out_truth * upstream.to(torch::kDouble)).sum().backward();
    const auto check = [](const torch::Tensor& fused_value, const torch::Tensor& ref_value,
                          const torch::Tensor& truth_value, const std::string& what) {
        const double e_fused = RelError(fused_value, truth_value);
        const double e_ref = RelError(ref_value, truth_value);
        std::cout << what << ": relative error fused " << e_fused << ", LibTorch " << e_ref << "\n";
        EXPECT_LE(e_fused, std::max(4 * e_ref, 1e-5)) << what;
    };
    check(out_fused, out_ref, out_truth, "output");
    check(rows_fused.grad(), rows_ref.grad(), rows_truth.grad(), "d rows");
    for (size_t s = 0; s < ref.size(); ++s) {
        const std::string st = "stage " + std::to_string(s + 1) + ": ";
        check(fused[s].weight.grad(), ref[s].weight.grad(), truth[s].weight.grad(),
              st + "d weight");
        check(fused[s].bn_weight.grad(), ref[s].bn_weight.grad(), truth[s].bn_weight.grad(),
              st + "d bn weight");
        check(fused[s].bn_bias.grad(), ref[s].bn_bias.grad(), truth[s].bn_bias.grad(),
              st + "d bn bias");
        check(fused[s].running_mean, ref[s].running_mean, truth[s].running_mean,
              st + "running mean");
        check(fused[s].running_var, ref[s].running_var, truth[s].running_var, st + "running var");
    }
}

// Exact positive ties (coincident neighbours give identical edge rows): the max takes the first
// of the tied neighbours, as torch::max's indices do, so the gradient lands on the same row.
TEST(EdgeStages, TiesGoToTheFirstNeighbourAsTorchMax) {
    torch::manual_seed(4);
    const int64_t points = 50, k = 6;
    torch::Tensor rows = torch::randn({points, k, 6}, torch::kDouble);
    rows.select(1, 3).copy_(rows.select(1, 1));  // neighbours 1 and 3 coincide
    rows.select(1, 5).copy_(rows.select(1, 1));
    rows = rows.reshape({points * k, 6});
    // torch::max's convention on this build: the first index of the tied values.
    const torch::Tensor probe = torch::tensor({1.0, 2.0, 2.0, 0.5});
    ASSERT_EQ(std::get<1>(probe.max(0)).item<int64_t>(), 1);
    CompareWithReference(rows, {6, 8, 8}, k, 1e-10);
}

// The fused path inside Dgcnn (training mode) against the same module with the reference
// composition: output, every parameter's gradient and the running statistics.
TEST(EdgeStages, DgcnnTrainingForwardAndBackwardMatchTheReferencePath) {
    torch::manual_seed(5);
    Dgcnn fused(32, 8);
    Dgcnn ref(32, 8);
    {
        torch::NoGradGuard no_grad;
        const auto src = fused->named_parameters();
        for (auto& p : ref->named_parameters()) p.value().copy_(src[p.key()]);
    }
    fused->train();
    ref->train();
    const torch::Tensor xyz = torch::rand({2, 3, 90}) - 0.5;
    SetFusedEdgeStages(false);
    const torch::Tensor out_ref = ref->forward(xyz);
    SetFusedEdgeStages(true);
    const torch::Tensor out_fused = fused->forward(xyz);
    ExpectClose(out_fused, out_ref, 1e-4, "dgcnn output");
    const torch::Tensor upstream = torch::randn(out_ref.sizes());
    (out_ref * upstream).sum().backward();
    (out_fused * upstream).sum().backward();
    const auto ref_params = ref->named_parameters();
    for (const auto& p : fused->named_parameters()) {
        ExpectClose(p.value().grad(), ref_params[p.key()].grad(), 1e-3, "d " + p.key());
    }
    const auto ref_buffers = ref->named_buffers();
    for (const auto& b : fused->named_buffers()) {
        if (b.value().scalar_type() == torch::kLong) {
            EXPECT_TRUE(torch::equal(b.value(), ref_buffers[b.key()])) << b.key();
        } else {
            ExpectClose(b.value(), ref_buffers[b.key()], 1e-4, b.key());
        }
    }
}

// The fused passes run in fixed chunks of points on LibTorch's threads and add the chunks' sums
// in order, so the result does not depend on the thread count (bit for bit).
TEST(EdgeStages, ResultsDoNotDependOnTheThreadCount) {
    torch::manual_seed(6);
    const int64_t points = 400, k = 10;
    const torch::Tensor rows = torch::randn({points * k, 6});
    const std::vector<EdgeStage> base = RandomStages({6, 16, 32}, torch::kFloat);
    std::vector<torch::Tensor> results[2];
    for (int threads = 1; threads <= 2; ++threads) {
        torch::set_num_threads(threads);
        const std::vector<EdgeStage> stages = Copy(base);
        const torch::Tensor in = rows.clone().requires_grad_();
        const torch::Tensor out = EdgeStagesFused(in, stages, k);
        out.pow(2).sum().backward();
        results[threads - 1] = {out, in.grad(), stages[0].weight.grad(), stages[1].bn_weight.grad(),
                                stages[1].running_var};
    }
    torch::set_num_threads(1);
    for (size_t i = 0; i < results[0].size(); ++i) {
        EXPECT_TRUE(torch::equal(results[0][i], results[1][i])) << "tensor " << i;
    }
}

TEST(EdgeStages, RefusesRowsThatAreNotWholePoints) {
    const std::vector<EdgeStage> stages = RandomStages({6, 8}, torch::kFloat);
    EXPECT_THROW(EdgeStagesFused(torch::randn({10, 6}), stages, 3), std::invalid_argument);
    EXPECT_THROW(EdgeStagesFused(torch::randn({9, 5}), stages, 3), std::invalid_argument);
}

}  // namespace
}  // namespace regbench::networks
