// The `regbench` Python module: pair files as NumPy arrays, every registered method and metric,
// and Python callables benchmarked as methods by the C++ runner. A thin layer: every check,
// timing, row and file format is the C++ core's; this file converts types and errors.
#include <Python.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/metrics.hpp"
#include "core/threads.hpp"
#include "core/transform.hpp"
#include "core/version.hpp"
#include "protocols/pair_file.hpp"
#include "python/callable_method.hpp"
#include "python/convert.hpp"
#include "python/gil.hpp"
#include "reports/versus.hpp"
#include "runners/align_clouds.hpp"
#include "runners/registry.hpp"
#include "runners/result_row.hpp"
#include "runners/runner.hpp"
#include "runners/scale_guard.hpp"

namespace regbench::python {
namespace {

/// os.fspath(path) as a std::string (str and os.PathLike accepted).
std::string PathOf(py::handle path) {
    return py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>();
}

/// FileNotFoundError for an input that is not there.
void RequireFile(const std::string& path, const std::string& what) {
    if (!std::filesystem::exists(path)) {
        PyErr_SetString(PyExc_FileNotFoundError, (path + ": no such " + what).c_str());
        throw py::error_already_set();
    }
}

// ---------------------------------------------------------------------------------------------
// Pair files

struct PairFile {
    std::string path;
    std::shared_ptr<const PairSet> set;
    DataTag data;  ///< provenance tag every result row on this file carries
};

struct PairRef {
    std::shared_ptr<const PairFile> file;
    std::size_t index = 0;
    const Pair& pair() const { return file->set->pairs[index]; }
};

std::shared_ptr<PairFile> OpenPairFile(py::handle path_like) {
    auto f = std::make_shared<PairFile>();
    f->path = PathOf(path_like);
    RequireFile(f->path, "pair file");
    try {
        WithoutGil([&] {
            auto set = std::make_shared<PairSet>(ReadPairFile(f->path));
            f->data = DataTagOf(f->path, *set);  // checks the stored content hash
            f->set = std::move(set);
        });
    } catch (const std::runtime_error& e) {
        throw py::value_error(e.what());  // the file's content: bad input
    }
    return f;
}

py::dict DataTagToPy(const DataTag& d) {
    nlohmann::json j = d;
    return JsonToPy(j);
}

PairRef PairAt(const std::shared_ptr<PairFile>& f, py::ssize_t k) {
    const auto n = static_cast<py::ssize_t>(f->set->pairs.size());
    if (k < 0) k += n;
    if (k < 0 || k >= n) {
        throw py::index_error("pair index out of range (" + std::to_string(n) + " pairs)");
    }
    return PairRef{f, static_cast<std::size_t>(k)};
}

/// Iterator over a pair file's pairs.
struct PairIterator {
    std::shared_ptr<PairFile> file;
    std::size_t next = 0;
};

py::array LabelView(const Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1>& labels,
                    py::handle owner) {
    py::array view(py::dtype::of<std::uint8_t>(), {static_cast<py::ssize_t>(labels.size())},
                   {static_cast<py::ssize_t>(1)}, labels.data(), owner);
    return view;
}

/// Getter of a Pair property that is a no-copy view of one of the pair's arrays (`view`:
/// CloudView or LabelView); the view keeps the Pair object, and with it the PairFile, alive.
template <class Array>
auto PairArrayView(Array Pair::*array, py::array (*view)(const Array&, py::handle)) {
    return [array, view](py::object self) {
        return view(self.cast<const PairRef&>().pair().*array, self);
    };
}

/// The shortcuts to the file's DataTag that Pair and PairFile share; `tag(object)` is the
/// object's DataTag.
template <class T, class... Extra, class GetTag>
void DefDataTagShortcuts(py::class_<T, Extra...>& cls, GetTag tag) {
    cls.def_property_readonly(
           "content_hash", [tag](const T& x) { return tag(x).content_hash; },
           "Hash of the pairs' arrays (rows' data.content_hash).")
        .def_property_readonly("dataset", [tag](const T& x) { return tag(x).dataset; })
        .def_property_readonly("protocol", [tag](const T& x) { return tag(x).protocol; })
        .def_property_readonly("pairing", [tag](const T& x) { return tag(x).pairing; })
        .def_property_readonly(
            "seed", [tag](const T& x) { return JsonToPy(tag(x).seed); },
            "Generation seed (None when unknown); seeds methods' streams.");
}

// ---------------------------------------------------------------------------------------------
// Methods

/// One validated built-in method spec (the checks `regbench run --params` applies).
MethodSpec BuiltinSpec(const std::string& name, const nlohmann::json& params) {
    FindMethod(name);  // unknown names: ValueError listing the known ones
    nlohmann::json by_method = nlohmann::json::object();
    by_method[name] = params;
    return ParseMethodSpecs(name, by_method).front();
}

py::list Methods() {
    py::list out;
    for (const auto& m : AllMethods()) {
        py::dict d;
        d["name"] = m.name;
        d["summary"] = m.summary;
        d["defaults"] = JsonToPy(m.defaults);
        d["param_docs"] = JsonToPy(nlohmann::json(m.param_docs));
        d["schema"] = JsonToPy(m.schema);
        out.append(d);
    }
    return out;
}

/// What align() returns: the method's result plus which method and parameters produced it.
struct AlignOutcome {
    std::string method;
    nlohmann::json params;
    AlignResult result;
};

AlignOutcome Align(py::handle source, py::handle target, const std::string& method,
                   py::handle params, std::uint64_t seed, int threads, std::uint64_t pair_index,
                   bool normalize, std::size_t max_points) {
    if (threads < 1) throw py::value_error("threads must be >= 1, got " + std::to_string(threads));
    const MethodSpec spec = BuiltinSpec(method, ParamsToJson(params, "params"));
    const PointCloud src = CloudFromPy(source, "source");
    const PointCloud tgt = CloudFromPy(target, "target");
    // run()'s scale guard, before the method is made: rienet on 200,000 points asked for 160 GB
    // and ended in a LibTorch backtrace.
    try {
        RequireCallScale(spec, static_cast<std::size_t>(src.rows()),
                         static_cast<std::size_t>(tgt.rows()), max_points);
    } catch (const std::invalid_argument& e) {
        throw py::value_error(std::string("align: ") + e.what() +
                              "; pass max_points=0 to run it as is (or a larger max_points), or "
                              "downsample the clouds first");
    }
    std::unique_ptr<RegistrationMethod> reg = CreateMethod(spec.name, spec.params);
    AlignContext context;
    context.seed = seed;
    context.pair_index = pair_index;
    context.threads = threads;
    SetOmpThreads(threads);  // setenv: before other threads may run
    AlignOutcome out{spec.name, spec.params, {}};
    out.result = WithoutGil([&] { return AlignClouds(*reg, src, tgt, normalize, context); });
    return out;
}

// ---------------------------------------------------------------------------------------------
// Metrics

py::dict Metrics(py::handle T_est, py::handle T_gt, py::handle source, py::handle target,
                 const std::string& euler, py::handle source_overlap) {
    const EulerConvention convention = ParseEulerConvention(euler);
    const Transform est = TransformFromPy(T_est, "T_est");
    const Transform gt = TransformFromPy(T_gt, "T_gt");
    const PointCloud src = CloudFromPy(source, "source");
    const PointCloud tgt = CloudFromPy(target, "target");
    Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1> labels;
    if (!source_overlap.is_none()) {
        const auto a = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>::ensure(
            source_overlap);
        if (!a || a.ndim() != 1 || a.shape(0) != src.rows()) {
            throw py::value_error("source_overlap must be a 1-D array of " +
                                  std::to_string(src.rows()) + " labels (0 or 1)");
        }
        labels =
            Eigen::Map<const Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1>>(a.data(), a.shape(0));
    }
    const PairMetrics m = WithoutGil([&] {
        PairMetrics r = ComputeMetrics(gt, est, src, tgt, convention);
        r.overlap_rmse = OverlapRmse(gt, est, src, labels);
        return r;
    });
    py::dict d;
    for (const auto& f : PerPairMetrics()) d[f.name] = m.*f.field;
    d["ccd_within_clip"] = m.ccd_within_clip;
    d["euler"] = ToString(m.euler);
    return d;
}

// ---------------------------------------------------------------------------------------------
// Runs

/// A callable's method name as UTF-8, checked: every row, OUT.part (which resume reads back)
/// and the report tables hold it. Throws ValueError naming the name (as repr) and the problem.
std::string CheckedMethodName(const py::str& name) {
    const std::string shown = py::repr(name).cast<std::string>();
    // py::str -> std::string is a pybind11 cast error for a str that UTF-8 cannot encode.
    const py::object utf8 = py::reinterpret_steal<py::object>(PyUnicode_AsUTF8String(name.ptr()));
    if (!utf8) {
        PyErr_Clear();
        throw py::value_error("method name " + shown +
                              " cannot be encoded as UTF-8 (a lone surrogate, as os.fsdecode "
                              "makes of undecodable bytes); result rows are UTF-8 JSON");
    }
    const std::string s = utf8.cast<py::bytes>();
    if (s.empty()) {
        throw py::value_error("method name is empty: pass the callable as (name, callable)");
    }
    for (const unsigned char c : s) {
        if (c < 0x20 || c == 0x7f) {
            throw py::value_error("method name " + shown +
                                  " contains a control character (a newline would split the "
                                  "rows of the report tables)");
        }
    }
    if (s.find_first_of(", ") != std::string::npos) {
        throw py::value_error("method name " + shown + " must not contain commas or spaces");
    }
    return s;
}

/// The name a callable runs under: the tuple's name, else its __name__ (checked).
std::string CallableName(py::handle item, py::handle* fn) {
    if (py::isinstance<py::tuple>(item)) {
        const py::tuple t = item.cast<py::tuple>();
        if (t.size() != 2 || !py::isinstance<py::str>(t[0]) || !PyCallable_Check(t[1].ptr())) {
            throw py::value_error("a method given as a tuple must be (name, callable)");
        }
        *fn = t[1];
        return CheckedMethodName(t[0].cast<py::str>());
    }
    *fn = item;
    const py::str name = py::hasattr(item, "__name__") ? py::str(item.attr("__name__")) : py::str();
    if (py::len(name) == 0 || name.equal(py::str("<lambda>"))) {
        throw py::value_error("cannot name the callable " + py::repr(item).cast<std::string>() +
                              ": pass it as (name, callable)");
    }
    return CheckedMethodName(name);
}

/// Adds `methods` to o.methods in the order given: names of built-in methods ("a,b" and "all"
/// too) and callables, each with its entry of `by_method` (run()'s `params`); callables also
/// go to o.external_methods. Throws Python's TypeError / ValueError naming the bad item.
void AddMethods(py::handle methods, const nlohmann::json& by_method,
                const std::shared_ptr<PendingInterrupt>& pending, RunOptions& o) {
    const auto params_of = [&](const std::string& name) {
        return by_method.contains(name) ? by_method.at(name) : nlohmann::json::object();
    };

    py::list items;
    const bool named_callable = py::isinstance<py::tuple>(methods) && py::len(methods) == 2 &&
                                py::isinstance<py::str>(methods[py::int_(0)]) &&
                                PyCallable_Check(methods[py::int_(1)].ptr());
    if (py::isinstance<py::str>(methods) || named_callable || PyCallable_Check(methods.ptr())) {
        items.append(methods);  // one method
    } else if (!py::isinstance<py::iterable>(methods)) {
        throw py::type_error("methods must be a list of method names and callables");
    } else {
        for (const auto& item : methods) items.append(item);
    }
    const ForkHooks fork_hooks = InterpreterForkHooks();
    for (const auto& item : items) {
        if (py::isinstance<py::str>(item)) {
            const std::vector<MethodSpec> specs =
                ParseMethodSpecs(item.cast<std::string>(), nlohmann::json::object());
            for (const auto& s : specs) o.methods.push_back(BuiltinSpec(s.name, params_of(s.name)));
            continue;
        }
        py::handle fn;
        const std::string name = CallableName(item, &fn);
        if (!PyCallable_Check(fn.ptr())) {
            throw py::type_error("methods must be names of built-in methods or callables, got " +
                                 py::repr(item).cast<std::string>());
        }
        bool registered = true;
        try {
            FindMethod(name);
        } catch (const std::invalid_argument&) {
            registered = false;
        }
        if (registered) {
            throw py::value_error("'" + name +
                                  "' is a built-in method; pass the callable as (other_name, fn)");
        }
        const nlohmann::json p = params_of(name);
        if (!p.is_object()) throw py::value_error("params['" + name + "'] must be a dict");
        o.methods.push_back(MethodSpec{name, p});
        ExternalMethod external;
        external.create = [name, p, fn, pending] {
            return std::make_unique<CallableMethod>(name, p, fn, pending);
        };
        external.fork_hooks = fork_hooks;
        o.external_methods[name] = external;
    }
    if (o.methods.empty()) throw py::value_error("no methods given");
    for (std::size_t i = 0; i < o.methods.size(); ++i) {
        for (std::size_t k = 0; k < i; ++k) {
            if (o.methods[k].name == o.methods[i].name) {
                throw py::value_error("method '" + o.methods[i].name + "' listed twice");
            }
        }
    }
    for (const auto& item : by_method.items()) {
        bool listed = false;
        for (const auto& m : o.methods) listed = listed || m.name == item.key();
        if (!listed) {
            throw py::value_error("params names method '" + item.key() +
                                  "' which is not in methods");
        }
    }
}

py::dict Run(py::handle pairs, py::handle methods, py::handle out, py::handle params, bool resume,
             py::handle timeout, int jobs, int threads, const std::string& euler,
             std::size_t max_points, bool downsample, bool progress) {
    RunOptions o;
    try {
        o.pairs_path =
            py::isinstance<PairFile>(pairs) ? pairs.cast<const PairFile&>().path : PathOf(pairs);
    } catch (const py::cast_error&) {
        throw py::type_error("pairs must be a path or a PairFile");
    }
    RequireFile(o.pairs_path, "pair file");
    o.out_path = PathOf(out);
    o.resume = resume;
    o.jobs = jobs;
    o.threads_per_call = threads;
    o.euler = ParseEulerConvention(euler);
    o.max_points = max_points;
    o.downsample = downsample;
    o.progress = progress;
    if (!timeout.is_none()) {
        if (!py::isinstance<py::float_>(timeout) && !py::isinstance<py::int_>(timeout)) {
            throw py::type_error("timeout must be a number of seconds or None");
        }
        o.timeout_seconds = PyFloat_AsDouble(timeout.ptr());  // an int beyond a double: error
        if (PyErr_Occurred()) PyErr_Clear();
        // As --timeout: finite (rows record it as JSON, which has no inf; resume compares it).
        if (!std::isfinite(o.timeout_seconds) || !(o.timeout_seconds > 0.0)) {
            throw py::value_error("timeout must be a finite number of seconds > 0 (or None), got " +
                                  py::repr(timeout).cast<std::string>());
        }
    }
    const auto pending = std::make_shared<PendingInterrupt>();
    AddMethods(methods, ParamsToJson(params, "params"), pending, o);
    // Ctrl-C stays Python's: between calls the runner asks whether one arrived (only the main
    // thread can see it) or a callable raised KeyboardInterrupt / SystemExit.
    const unsigned long caller = PyThread_get_thread_ident();
    o.check_interrupt = [pending, caller] {
        pending->RethrowIfAny();
        if (PyThread_get_thread_ident() == caller) {
            const GilAcquired gil;
            if (PyErr_CheckSignals() != 0) throw py::error_already_set();
        }
    };
    SetOmpThreads(threads >= 1 ? threads : 1);
    RunSummary s;
    try {
        s = WithoutGil([&] { return RunBenchmark(o); });
    } catch (const std::runtime_error& e) {
        // Problems of the pair file are bad input; the rest (locks, writes, resume) are not.
        const std::string what = e.what();
        if (what.rfind(o.pairs_path + ":", 0) == 0) throw py::value_error(what);
        throw;
    }
    py::dict d;
    d["out"] = o.out_path;
    d["rows_written"] = s.rows_written;
    d["rows_skipped"] = s.rows_skipped;
    d["failures"] = s.failures;
    d["wall_seconds"] = s.wall_seconds;
    return d;
}

py::object ReadResults(py::handle path_like, py::handle as_frame) {
    const std::string path = PathOf(path_like);
    RequireFile(path, "results file");
    std::vector<ResultRow> rows;
    try {
        rows = ReadResultRows(path);
    } catch (const std::exception& e) {
        throw py::value_error(e.what());
    }
    py::list out;
    for (const auto& row : rows) out.append(JsonToPy(nlohmann::json(row)));
    if (!as_frame.is_none() && !as_frame.cast<bool>()) return std::move(out);
    py::module_ pandas;
    try {
        pandas = py::module_::import("pandas");
    } catch (const py::error_already_set& e) {
        if (as_frame.is_none() && e.matches(PyExc_ImportError)) return std::move(out);
        throw;
    }
    return pandas.attr("json_normalize")(out, py::arg("max_level") = 1);
}

/// compare_methods: method A against method B on their common pairs (reports/versus.hpp), from
/// one results file or several.
py::list CompareMethodsPy(py::handle results, const std::string& a, const std::string& b,
                          int bootstrap, std::uint64_t seed) {
    std::vector<std::string> paths;
    if (py::isinstance<py::str>(results) || py::hasattr(results, "__fspath__")) {
        paths.push_back(PathOf(results));
    } else {
        for (py::handle item : results) paths.push_back(PathOf(item));
    }
    if (bootstrap < 2) throw py::value_error("bootstrap must be >= 2");
    std::vector<ResultRow> rows;
    VersusOptions o;
    o.bootstrap_samples = bootstrap;
    o.seed = seed;
    py::list out;
    try {
        for (const auto& path : paths) {
            RequireFile(path, "results file");
            auto part = ReadResultRows(path);
            rows.insert(rows.end(), part.begin(), part.end());
        }
        for (const auto& r : CompareMethods(rows, a, b, o)) out.append(JsonToPy(VersusToJson(r)));
    } catch (const py::error_already_set&) {
        throw;
    } catch (const std::exception& e) {
        throw py::value_error(e.what());
    }
    return out;
}

/// Pair: one pair of a pair file, its clouds as NumPy views.
void BindPair(py::module_& m) {
    py::class_<PairRef> pair(m, "Pair",
                             "One pair of a pair file. `source` and `target` are (N, 3) float64 "
                             "views of the PairFile's arrays (no copy; writing to them changes "
                             "what this PairFile returns, never the file); `T_gt` maps source "
                             "into the target frame.");
    pair.def_property_readonly(
            "index", [](const PairRef& p) { return p.index; },
            "Index of the pair in its file (the rows' `pair`).")
        .def_property_readonly("source", PairArrayView(&Pair::source, CloudView),
                               "Source cloud, (N, 3) float64 view.")
        .def_property_readonly("target", PairArrayView(&Pair::target, CloudView),
                               "Target cloud, (M, 3) float64 view.")
        .def_property_readonly(
            "T_gt", [](const PairRef& p) { return TransformToPy(p.pair().T_gt); },
            "Ground truth (4, 4): target ~ T_gt applied to source.")
        .def_property_readonly("source_overlap", PairArrayView(&Pair::source_overlap, LabelView),
                               "Per source point: 1 = overlaps the target (uint8).")
        .def_property_readonly("target_overlap", PairArrayView(&Pair::target_overlap, LabelView),
                               "Per target point: 1 = overlaps the source (uint8).")
        .def_property_readonly(
            "source_overlap_ratio", [](const PairRef& p) { return p.pair().source_overlap_ratio; },
            "Fraction of source points labelled overlapping.")
        .def_property_readonly(
            "target_overlap_ratio", [](const PairRef& p) { return p.pair().target_overlap_ratio; },
            "Fraction of target points labelled overlapping.")
        .def_property_readonly(
            "overlap", [](const PairRef& p) { return p.pair().source_overlap_ratio; },
            "The pair's overlap: source_overlap_ratio (what reports bin by).")
        .def_property_readonly(
            "shape", [](const PairRef& p) { return p.pair().shape; }, "Mesh / scan name.")
        .def_property_readonly(
            "category", [](const PairRef& p) { return p.pair().category; },
            "Category of the shape (may be empty).")
        .def_property_readonly(
            "meta", [](const PairRef& p) { return JsonToPy(p.pair().meta); },
            "Per-pair generation details (dict).")
        .def_property_readonly(
            "data", [](const PairRef& p) { return DataTagToPy(p.file->data); },
            "Provenance tag of the file, as result rows carry it: pairs_file, "
            "dataset, protocol, pairing, seed, content_hash.")
        .def("__repr__", [](const PairRef& p) {
            const Pair& q = p.pair();
            return "<regbench.Pair " + std::to_string(p.index) + " of " + p.file->data.pairs_file +
                   ": " + q.shape + (q.category.empty() ? "" : " (" + q.category + ")") + ", " +
                   std::to_string(q.source.rows()) + " -> " + std::to_string(q.target.rows()) +
                   " points, overlap " + std::to_string(q.source_overlap_ratio) + ">";
        });
    DefDataTagShortcuts(pair, [](const PairRef& p) -> const DataTag& { return p.file->data; });
}

/// PairFile and its iterator.
void BindPairFile(py::module_& m) {
    py::class_<PairIterator>(m, "_PairIterator")
        .def("__iter__", [](py::object self) { return self; })
        .def("__next__", [](PairIterator& it) {
            if (it.next >= it.file->set->pairs.size()) throw py::stop_iteration();
            return PairRef{it.file, it.next++};
        });

    py::class_<PairFile, std::shared_ptr<PairFile>> pair_file(
        m, "PairFile",
        "PairFile(path): a frozen HDF5 pair file (regbench generate / import), read and "
        "validated by the C++ reader. Raises FileNotFoundError, or ValueError with the reader's "
        "message (\"FILE: pair K: ...\") for a damaged or modified file.");
    pair_file.def(py::init(&OpenPairFile), py::arg("path"))
        .def("__len__", [](const PairFile& f) { return f.set->pairs.size(); })
        .def("__getitem__", &PairAt, py::arg("index"))
        .def("__iter__",
             [](const std::shared_ptr<PairFile>& f) {
                 return PairIterator{f, 0};
             })
        .def_property_readonly("path", [](const PairFile& f) { return f.path; })
        .def_property_readonly(
            "provenance", [](const PairFile& f) { return JsonToPy(f.set->provenance); },
            "The file's provenance (protocol, params, seed, dataset, ...).")
        .def_property_readonly(
            "data", [](const PairFile& f) { return DataTagToPy(f.data); },
            "Provenance tag as result rows carry it.")
        .def("__repr__", [](const PairFile& f) {
            return "<regbench.PairFile " + f.path + ": " + std::to_string(f.set->pairs.size()) +
                   " pairs, dataset " + f.data.dataset + ", protocol " + f.data.protocol +
                   ", content " + f.data.content_hash + ">";
        });
    DefDataTagShortcuts(pair_file, [](const PairFile& f) -> const DataTag& { return f.data; });
}

/// align() with its AlignResult, and metrics().
void BindAlign(py::module_& m) {
    py::class_<AlignOutcome>(m, "AlignResult", "What align() returns.")
        .def_property_readonly("method", [](const AlignOutcome& a) { return a.method; })
        .def_property_readonly(
            "params", [](const AlignOutcome& a) { return JsonToPy(a.params); },
            "The method's full parameters (defaults filled in).")
        .def_property_readonly(
            "T_target_source",
            [](const AlignOutcome& a) { return TransformToPy(a.result.T_target_source); },
            "Estimate (4, 4) mapping source into the target frame (identity "
            "when the call failed).")
        .def_property_readonly("iterations",
                               [](const AlignOutcome& a) { return a.result.iterations; })
        .def_property_readonly("stop_reason",
                               [](const AlignOutcome& a) { return a.result.stop_reason; })
        .def_property_readonly(
            "status", [](const AlignOutcome& a) { return std::string(ToString(a.result.status)); },
            "\"ok\" or \"failed\" (then `message` says why).")
        .def_property_readonly("message", [](const AlignOutcome& a) { return a.result.message; })
        .def_property_readonly(
            "seconds", [](const AlignOutcome& a) { return a.result.seconds; },
            "Wall time of the method's call.")
        .def_property_readonly(
            "cpu_seconds", [](const AlignOutcome& a) { return a.result.cpu_seconds; },
            "CPU time of the call (clock named by cpu_scope).")
        .def_property_readonly("cpu_scope",
                               [](const AlignOutcome& a) { return a.result.cpu_scope; })
        .def_property_readonly("scale", [](const AlignOutcome& a) { return a.result.scale; })
        .def_property_readonly(
            "extra", [](const AlignOutcome& a) { return JsonToPy(a.result.extra); },
            "Method diagnostics (dict).")
        .def("__repr__", [](const AlignOutcome& a) {
            return "<regbench.AlignResult " + a.method + ": " + ToString(a.result.status) + ", " +
                   std::to_string(a.result.iterations) + " iterations (" + a.result.stop_reason +
                   "), " + std::to_string(a.result.seconds) + " s>";
        });

    m.def("align", &Align, py::arg("source"), py::arg("target"), py::arg("method") = "cpd",
          py::arg("params") = py::none(), py::arg("seed") = 0, py::arg("threads") = 1,
          py::arg("pair_index") = 0, py::arg("normalize") = false, py::kw_only(),
          py::arg("max_points") = kDefaultMaxPoints,
          "align(source, target, method=\"cpd\", params=None, seed=0, threads=1, pair_index=0, "
          "normalize=False, *, max_points=20000) -> AlignResult\n\n"
          "Registers source onto target with a built-in method, the interpreter lock released "
          "while C++ works. source, target: (N, 3) float arrays. seed and pair_index pick the "
          "method's random stream as `regbench run` does for pair `pair_index` of a file "
          "generated with `seed`. normalize: as `regbench align --normalize`. max_points: "
          "run()'s scale guard: a method that is O(N*M) at this setting (rienet, rgm, regtr; "
          "cpd e_step dense, ...) on a cloud above max_points points raises ValueError (0 "
          "turns the guard off). A method that "
          "fails returns status \"failed\" and a message; bad input (unknown method or "
          "parameter, wrong shape or dtype, NaN) raises ValueError.");

    m.def("metrics", &Metrics, py::arg("T_est"), py::arg("T_gt"), py::arg("source"),
          py::arg("target"), py::arg("euler") = "zyx", py::arg("source_overlap") = py::none(),
          "metrics(T_est, T_gt, source, target, euler=\"zyx\", source_overlap=None) -> dict\n\n"
          "Every per-pair metric of docs/metrics.md for an estimate against the ground truth: "
          "mae_r, mse_r (degrees, Euler angles of `euler`: 'zyx' or 'xyz'), mae_t, mse_t, rre "
          "(degrees), rte, ccd, chamfer, ccd_within_clip, overlap_rmse (over the source points "
          "labelled 1 in source_overlap; all points when None), and euler.");
}

/// run() and read_results().
void BindRun(py::module_& m) {
    m.def("run", &Run, py::arg("pairs"), py::arg("methods"), py::arg("out"),
          py::arg("params") = py::none(), py::arg("resume") = false,
          py::arg("timeout") = py::none(), py::kw_only(), py::arg("jobs") = 1,
          py::arg("threads") = 1, py::arg("euler") = "zyx", py::arg("max_points") = 20000,
          py::arg("downsample") = false, py::arg("progress") = false,
          "run(pairs, methods, out, params=None, resume=False, timeout=None, *, jobs=1, "
          "threads=1, euler=\"zyx\", max_points=20000, downsample=False, progress=False) -> "
          "dict\n\n"
          "`regbench run` with Python callables as methods. methods: a list of built-in method "
          "names and callables fn(source, target, **params) -> 4x4 array (or a dict with "
          "\"transform\" and optional \"iterations\", \"stop_reason\" and extras); a callable "
          "runs under its __name__, or give (name, fn). params: {method name: {parameter: "
          "value}}. Rows, file format, resume, the output lock and atomic writes are those of "
          "`regbench run`; a callable is timed like a built-in method (wall and CPU), an "
          "exception in it becomes a `failed` row with its message, and with `timeout` it runs "
          "in a forked child. Ctrl-C stops the run with KeyboardInterrupt, the finished rows "
          "kept in OUT.part for resume=True. Returns {out, rows_written, rows_skipped, "
          "failures, wall_seconds}.");

    m.def("compare_methods", &CompareMethodsPy, py::arg("results"), py::arg("a"), py::arg("b"),
          py::arg("bootstrap") = 2000, py::arg("seed") = kDefaultBootstrapSeed,
          "compare_methods(results, a, b, bootstrap=2000, seed=20230103) -> list[dict]\n\n"
          "Method a against method b on the pairs both ran (results: one results file or a "
          "list of them), as `regbench report --versus a,b`: one dict per pair file with "
          "method_a, method_b, data, euler, pairs_a, pairs_b, common, failed_a, failed_b, "
          "bootstrap_samples and metrics, a list of {metric, pairs, mean_a, mean_b, diff_mean "
          "(a - b), ci_lo, ci_hi, p_value (95% CI and two-sided p of one paired bootstrap of "
          "the mean difference), differs (the CI excludes 0), verdict (one line), wins, ties, "
          "losses (of a; lower error wins)}.");
    m.def("read_results", &ReadResults, py::arg("path"), py::arg("as_frame") = py::none(),
          "read_results(path, as_frame=None) -> pandas.DataFrame | list[dict]\n\n"
          "Reads a results file (`run`, `score`, `merge`), each row validated by the C++ "
          "reader. A pandas DataFrame (nested keys one level flattened: metrics.mae_r, "
          "data.content_hash, params.w, ...) when pandas is importable and as_frame is not "
          "False, else a list of dicts.");
}

}  // namespace
}  // namespace regbench::python

PYBIND11_MODULE(regbench, m) {
    using namespace regbench;
    using namespace regbench::python;
    m.doc() =
        "regbench from Python: frozen pair files as NumPy arrays, every registered method and "
        "metric, and Python callables benchmarked beside the built-in methods by the same "
        "runner (timing, failures, timeouts, resume, result rows). See docs/python.md.";
    m.attr("__version__") = std::string(RegbenchVersion()) + "+g" + RegbenchGitSha();

    m.def("methods", &Methods,
          "methods() -> list[dict]\n\n"
          "Every registered method: name, summary, defaults (every parameter with its default), "
          "param_docs (one line per parameter) and schema (JSON Schema, or None), as "
          "`regbench methods --json` prints them.");

    BindPair(m);
    BindPairFile(m);
    BindAlign(m);
    BindRun(m);
}
