// regbench-train-portable: `regbench train` for a machine that has LibTorch and a C++ compiler
// but none of Open3D, PCL, CGAL, HDF5 or CLI11 (a GPU node). It trains from a training bundle
// that `regbench train ... --write-bundle FILE` wrote, on the same pair stream, and writes the
// same run directory (last/, best/, metrics.csv), which `regbench train --resume` and every
// command that takes a checkpoint read. Validation has no ICP here (Open3D): the "with ICP"
// columns stay empty. The arguments are parsed by hand because CLI11 is one of the libraries
// such a machine lacks.
#include <cstdint>
#include <exception>
#include <iostream>
#include <optional>
#include <string>
#include <string_view>

#include "core/parse_number.hpp"
#include "experiments/training_bundle.hpp"
#include "networks/training/train.hpp"

namespace {

constexpr const char* kUsage =
    "usage: regbench-train-portable BUNDLE --out DIR [--device cpu|cuda] [--minutes M]\n"
    "                              [--max-steps S] [--resume] [--threads T]\n"
    "Trains the model of BUNDLE (written by `regbench train ... --write-bundle BUNDLE`) into "
    "DIR.\n";

struct Args {
    std::string bundle;
    regbench::networks::TrainOptions train;
    std::string command = "regbench-train-portable";
};

template <typename T>
T Number(std::string_view flag, const char* text, bool positive) {
    const std::optional<T> v = regbench::ParseNumber<T>(text);
    if (!v || !(*v == *v) || (positive && !(*v > 0))) {
        throw std::invalid_argument(std::string(flag) + " needs a " +
                                    (positive ? "positive " : "") + "number, got '" + text + "'");
    }
    return *v;
}

Args Parse(int argc, char** argv) {
    Args a;
    for (int i = 1; i < argc; ++i) {
        const std::string_view arg = argv[i];
        a.command += " " + std::string(arg);
        auto value = [&]() -> const char* {
            if (i + 1 >= argc) throw std::invalid_argument(std::string(arg) + " needs a value");
            a.command += " " + std::string(argv[i + 1]);
            return argv[++i];
        };
        if (arg == "--out") {
            a.train.out_dir = value();
        } else if (arg == "--device") {
            a.train.device = value();
        } else if (arg == "--minutes") {
            a.train.minutes = Number<double>(arg, value(), true);
        } else if (arg == "--max-steps") {
            a.train.max_steps = Number<std::int64_t>(arg, value(), true);
        } else if (arg == "--threads") {
            a.train.threads = Number<int>(arg, value(), true);
        } else if (arg == "--resume") {
            a.train.resume = true;
        } else if (arg == "--help" || arg == "-h") {
            std::cout << kUsage;
            std::exit(0);
        } else if (arg.substr(0, 1) != "-" && a.bundle.empty()) {
            a.bundle = arg;
        } else {
            throw std::invalid_argument("unknown argument '" + std::string(arg) + "'");
        }
    }
    if (a.bundle.empty()) throw std::invalid_argument("no BUNDLE given");
    if (a.train.out_dir.empty()) throw std::invalid_argument("--out is required");
    return a;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        Args a = Parse(argc, argv);
        const regbench::TrainingBundle bundle = regbench::ReadTrainingBundle(a.bundle);
        if (!bundle.config.is_object()) {
            throw std::invalid_argument("training bundle " + a.bundle +
                                        " holds no model config (write it with `regbench train "
                                        "--model NAME ... --write-bundle FILE`)");
        }
        const regbench::networks::TrainData data = regbench::MakeTrainingData(bundle);
        regbench::networks::TrainOptions& o = a.train;
        o.seed = bundle.seed;
        o.plan_to_budget = o.PlansToBudget(bundle.length_given);
        o.run_info = {
            {"command", a.command}, {"bundle", a.bundle}, {"bundle_command", bundle.command}};
        std::cerr << "train: " << bundle.config.value("name", std::string("?")) << " -> "
                  << o.out_dir << " (" << data.validation.size() << " validation pairs, "
                  << o.threads << " threads, " << o.device << ")\n";
        const regbench::networks::TrainSummary s = regbench::networks::Train(bundle.config, data, o);
        std::cerr << "train: done, " << s.steps << " steps; checkpoints " << o.out_dir << "/last, "
                  << o.out_dir << "/best\n";
        return 0;
    } catch (const std::exception& e) {
        std::cerr << "regbench-train-portable: " << e.what() << "\n";
        if (argc < 2) std::cerr << kUsage;
        return 1;
    }
}
