#include "gmm/bfgs.hpp"

#include <algorithm>
#include <cmath>

namespace regbench {
namespace {

constexpr double kStepMin = 1e-100;               // scipy's _minimize_bfgs passes amin = 1e-100
constexpr double kStepMax = 1e100;                // ... and amax = 1e100
constexpr double kRhoWhenCurvatureZero = 1000.0;  // scipy: "Divide-by-zero encountered"

/// The minimiser of the cubic through (stp, fp, dp) and (st, f, d), written from stp: dcstep's
/// case 2 (st = stx) and case 4 (st = sty) compute exactly this, operation for operation.
double CubicStepFrom(double stp, double fp, double dp, double st, double f, double d) {
    const double theta = 3.0 * (f - fp) / (stp - st) + d + dp;
    const double s = std::max({std::abs(theta), std::abs(d), std::abs(dp)});
    double gamma = s * std::sqrt((theta / s) * (theta / s) - (d / s) * (dp / s));
    if (stp > st) gamma = -gamma;
    const double p = (gamma - dp) + theta;
    const double q = ((gamma - dp) + gamma) + d;
    return stp + (p / q) * (st - stp);
}

/// MINPACK-2 dcstep: safeguarded cubic/quadratic step for the interval [stx, sty]
/// (Moré & Thuente 1994, Sec. 4, cases 1-4). Updates the interval and returns the new step.
/// Step() is long on purpose: it follows dcstep line by line (four cases sharing the interval
/// update), so it can be checked against the reference and against scipy's results.
struct Dcstep {
    double stx, fx, dx, sty, fy, dy;
    bool brackt = false;

    double Step(double stp, double fp, double dp, double stpmin, double stpmax) {
        constexpr double kP66 = 0.66;
        const double sgnd = dp * (dx / std::abs(dx));
        double stpf;
        if (fp > fx) {
            // Case 1: higher function value; the minimum is bracketed.
            const double theta = 3.0 * (fx - fp) / (stp - stx) + dx + dp;
            const double s = std::max({std::abs(theta), std::abs(dx), std::abs(dp)});
            double gamma = s * std::sqrt((theta / s) * (theta / s) - (dx / s) * (dp / s));
            if (stp < stx) gamma = -gamma;
            const double p = (gamma - dx) + theta;
            const double q = ((gamma - dx) + gamma) + dp;
            const double stpc = stx + (p / q) * (stp - stx);
            const double stpq = stx + ((dx / ((fx - fp) / (stp - stx) + dx)) / 2.0) * (stp - stx);
            stpf = std::abs(stpc - stx) < std::abs(stpq - stx) ? stpc : stpc + (stpq - stpc) / 2.0;
            brackt = true;
        } else if (sgnd < 0.0) {
            // Case 2: lower value, derivatives of opposite sign; bracketed.
            const double stpc = CubicStepFrom(stp, fp, dp, stx, fx, dx);
            const double stpq = stp + (dp / (dp - dx)) * (stx - stp);
            stpf = std::abs(stpc - stp) > std::abs(stpq - stp) ? stpc : stpq;
            brackt = true;
        } else if (std::abs(dp) < std::abs(dx)) {
            // Case 3: lower value, same-sign derivative, derivative magnitude decreases.
            const double theta = 3.0 * (fx - fp) / (stp - stx) + dx + dp;
            const double s = std::max({std::abs(theta), std::abs(dx), std::abs(dp)});
            double gamma =
                s * std::sqrt(std::max(0.0, (theta / s) * (theta / s) - (dx / s) * (dp / s)));
            if (stp > stx) gamma = -gamma;
            const double p = (gamma - dp) + theta;
            const double q = (gamma + (dx - dp)) + gamma;
            const double r = p / q;
            double stpc;
            if (r < 0.0 && gamma != 0.0) {
                stpc = stp + r * (stx - stp);
            } else {
                stpc = stp > stx ? stpmax : stpmin;
            }
            const double stpq = stp + (dp / (dp - dx)) * (stx - stp);
            if (brackt) {
                stpf = std::abs(stpc - stp) < std::abs(stpq - stp) ? stpc : stpq;
                stpf = stp > stx ? std::min(stp + kP66 * (sty - stp), stpf)
                                 : std::max(stp + kP66 * (sty - stp), stpf);
            } else {
                stpf = std::abs(stpc - stp) > std::abs(stpq - stp) ? stpc : stpq;
                stpf = std::max(stpmin, std::min(stpmax, stpf));
            }
        } else {
            // Case 4: lower value, same-sign derivative that does not decrease.
            if (brackt) {
                // 3 (fp - fy) / (sty - stp) there = 3 (fy - fp) / (stp - sty) here, exactly.
                stpf = CubicStepFrom(stp, fp, dp, sty, fy, dy);
            } else {
                stpf = stp > stx ? stpmax : stpmin;
            }
        }
        // Update the interval that contains a minimiser.
        if (fp > fx) {
            sty = stp;
            fy = fp;
            dy = dp;
        } else {
            if (sgnd < 0.0) {
                sty = stx;
                fy = fx;
                dy = dx;
            }
            stx = stp;
            fx = fp;
            dx = dp;
        }
        return stpf;
    }
};

/// MINPACK-2 dcsrch as a reverse-communication state machine; `Next` returns the task
/// ("FG" = evaluate at the returned step, "CONVERGENCE", "WARNING: ...", "ERROR: ...").
class Dcsrch {
public:
    Dcsrch(double ftol, double gtol, double xtol, double stpmin, double stpmax)
        : ftol_(ftol), gtol_(gtol), xtol_(xtol), stpmin_(stpmin), stpmax_(stpmax) {}

    /// First call: f, g at step 0 and the initial trial step.
    std::string Start(double& stp, double f, double g) {
        if (stp < stpmin_) return "ERROR: STP .LT. STPMIN";
        if (stp > stpmax_) return "ERROR: STP .GT. STPMAX";
        if (g >= 0.0) return "ERROR: INITIAL G .GE. ZERO";
        stage_ = 1;
        finit_ = f;
        ginit_ = g;
        gtest_ = ftol_ * ginit_;
        width_ = stpmax_ - stpmin_;
        width1_ = width_ / 0.5;
        st_ = Dcstep{0.0, finit_, ginit_, 0.0, finit_, ginit_};
        stmin_ = 0.0;
        stmax_ = stp + kXtrapu * stp;
        return "FG";
    }

    /// Later calls: f, g at the step last returned; may change stp.
    std::string Next(double& stp, double f, double g) {
        const double ftest = finit_ + stp * gtest_;
        // MINPACK-2 enters stage 2 once psi(stp) <= 0 and f'(stp) >= 0 (MINPACK-1's cvsrch used
        // min(ftol, gtol) f'(0) instead of 0).
        if (stage_ == 1 && f <= ftest && g >= 0.0) stage_ = 2;
        std::string task;
        if (st_.brackt && (stp <= stmin_ || stp >= stmax_)) {
            task = "WARNING: ROUNDING ERRORS PREVENT PROGRESS";
        }
        if (st_.brackt && stmax_ - stmin_ <= xtol_ * stmax_) task = "WARNING: XTOL TEST SATISFIED";
        if (stp == stpmax_ && f <= ftest && g <= gtest_) task = "WARNING: STP = STPMAX";
        if (stp == stpmin_ && (f > ftest || g >= gtest_)) task = "WARNING: STP = STPMIN";
        // Strong Wolfe conditions (Moré & Thuente eqs. (1.1)-(1.2)).
        if (f <= ftest && std::abs(g) <= gtol_ * (-ginit_)) task = "CONVERGENCE";
        if (!task.empty()) return task;

        if (stage_ == 1 && f <= st_.fx && f > ftest) {
            // Modified function psi(a) = f(a) - f(0) - ftol a f'(0) while in stage 1.
            Dcstep m{st_.stx,   st_.fx - st_.stx * gtest_, st_.dx - gtest_,
                     st_.sty,   st_.fy - st_.sty * gtest_, st_.dy - gtest_,
                     st_.brackt};
            stp = m.Step(stp, f - stp * gtest_, g - gtest_, stmin_, stmax_);
            st_ = Dcstep{m.stx,   m.fx + m.stx * gtest_, m.dx + gtest_,
                         m.sty,   m.fy + m.sty * gtest_, m.dy + gtest_,
                         m.brackt};
        } else {
            stp = st_.Step(stp, f, g, stmin_, stmax_);
        }
        if (st_.brackt) {
            // Bisect when the interval does not shrink enough.
            if (std::abs(st_.sty - st_.stx) >= kP66 * width1_) {
                stp = st_.stx + 0.5 * (st_.sty - st_.stx);
            }
            width1_ = width_;
            width_ = std::abs(st_.sty - st_.stx);
            stmin_ = std::min(st_.stx, st_.sty);
            stmax_ = std::max(st_.stx, st_.sty);
        } else {
            stmin_ = stp + kXtrapl * (stp - st_.stx);
            stmax_ = stp + kXtrapu * (stp - st_.stx);
        }
        stp = std::min(std::max(stp, stpmin_), stpmax_);
        if (st_.brackt && (stp <= stmin_ || stp >= stmax_ || stmax_ - stmin_ <= xtol_ * stmax_)) {
            stp = st_.stx;  // no further progress possible: return the best point
        }
        return "FG";
    }

private:
    static constexpr double kXtrapl = 1.1;
    static constexpr double kXtrapu = 4.0;
    static constexpr double kP66 = 0.66;
    double ftol_, gtol_, xtol_, stpmin_, stpmax_;
    int stage_ = 1;
    double finit_ = 0, ginit_ = 0, gtest_ = 0, width_ = 0, width1_ = 0;
    double stmin_ = 0, stmax_ = 0;
    Dcstep st_{0, 0, 0, 0, 0, 0};
};

}  // namespace

LineSearchResult MoreThuenteSearch(const BfgsObjective& fun, const Eigen::VectorXd& x,
                                   const Eigen::VectorXd& p, double f0, const Eigen::VectorXd& g0,
                                   double step0, const BfgsOptions& options) {
    LineSearchResult out;
    Dcsrch search(options.c1, options.c2, options.xtol, kStepMin, kStepMax);
    double stp = step0;
    double phi = f0;
    double dphi = g0.dot(p);
    Eigen::VectorXd grad = g0;
    out.task = search.Start(stp, phi, dphi);
    while (out.task == "FG") {
        if (out.evaluations == options.max_line_search_evals) {
            out.task = "WARNING: TOO MANY EVALUATIONS";
            break;
        }
        phi = fun(x + stp * p, grad);
        ++out.evaluations;
        dphi = grad.dot(p);
        out.task = search.Next(stp, phi, dphi);
    }
    out.ok = out.task == "CONVERGENCE";
    out.step = stp;
    out.f = phi;
    out.grad = grad;
    return out;
}

BfgsResult MinimizeBfgs(const BfgsObjective& fun, const Eigen::VectorXd& x0,
                        const BfgsOptions& options) {
    const Eigen::Index n = x0.size();
    BfgsResult r;
    r.x = x0;
    r.grad.resize(n);
    r.f = fun(r.x, r.grad);
    r.evaluations = 1;
    double old_old_f = r.f + r.grad.norm() / 2.0;  // scipy: gives a first step 1.01/|g0|
    Eigen::MatrixXd H = Eigen::MatrixXd::Identity(n, n);
    r.stop_reason = "max_iterations";
    if (!std::isfinite(r.f)) {
        r.stop_reason = "line_search_failed";
        return r;
    }
    while (r.grad.lpNorm<Eigen::Infinity>() > options.gtol) {
        if (r.iterations >= options.maxiter) return r;
        const Eigen::VectorXd p = -H * r.grad;
        const double dphi0 = r.grad.dot(p);
        // scipy's scalar_search_wolfe1 initial step.
        double step0 = 1.0;
        if (dphi0 != 0.0) {
            step0 = std::min(1.0, 1.01 * 2.0 * (r.f - old_old_f) / dphi0);
            if (step0 < 0.0) step0 = 1.0;
        }
        LineSearchResult ls = MoreThuenteSearch(fun, r.x, p, r.f, r.grad, step0, options);
        r.evaluations += ls.evaluations;
        if (!ls.ok) {
            r.stop_reason = "line_search_failed";
            return r;
        }
        const Eigen::VectorXd s = ls.step * p;
        const Eigen::VectorXd y = ls.grad - r.grad;
        old_old_f = r.f;
        r.x += s;
        r.f = ls.f;
        r.grad = ls.grad;
        ++r.iterations;
        if (r.grad.lpNorm<Eigen::Infinity>() <= options.gtol) break;
        if (!std::isfinite(r.f)) {
            r.stop_reason = "line_search_failed";
            return r;
        }
        // BFGS inverse-Hessian update (Nocedal & Wright eq. (6.17)).
        const double ys = y.dot(s);
        const double rho = ys == 0.0 ? kRhoWhenCurvatureZero : 1.0 / ys;
        const Eigen::MatrixXd A1 = Eigen::MatrixXd::Identity(n, n) - rho * s * y.transpose();
        const Eigen::MatrixXd A2 = Eigen::MatrixXd::Identity(n, n) - rho * y * s.transpose();
        H = A1 * H * A2 + rho * s * s.transpose();
    }
    r.stop_reason = "converged";
    return r;
}

}  // namespace regbench
