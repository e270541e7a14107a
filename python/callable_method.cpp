#include "python/callable_method.hpp"

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <new>
#include <stdexcept>

#include "python/convert.hpp"
#include "python/gil.hpp"

namespace regbench::python {

/// What a forked child hands to the run's process: state 0 nothing, 1 a child is writing,
/// 2 `text` holds the message of the KeyboardInterrupt to raise.
struct PendingInterrupt::Shared {
    std::atomic<int> state;
    char text[1024];
};
static_assert(std::atomic<int>::is_always_lock_free, "shared between processes");

PendingInterrupt::PendingInterrupt() : owner_pid_(static_cast<long>(::getpid())) {
    void* p =
        ::mmap(nullptr, sizeof(Shared), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) {
        throw std::runtime_error(std::string("run: cannot map the interrupt flag shared with "
                                             "timeout= children: ") +
                                 std::strerror(errno));
    }
    shared_ = new (p) Shared{};
}

PendingInterrupt::~PendingInterrupt() {
    shared_->~Shared();
    ::munmap(shared_, sizeof(Shared));
}

namespace {

/// The message of the KeyboardInterrupt that stands for `e`: a KeyboardInterrupt's own, else
/// "<Type> raised in a callable: <description>".
std::string InterruptText(const py::error_already_set& e) {
    if (e.matches(PyExc_KeyboardInterrupt)) return py::str(e.value()).cast<std::string>();
    return py::str(e.type().attr("__name__")).cast<std::string>() +
           " raised in a callable: " + DescribePythonError(e);
}

}  // namespace

void PendingInterrupt::Store(const py::error_already_set& e) {
    if (static_cast<long>(::getpid()) != owner_pid_) {
        // A forked child (timeout=): its memory dies with it; the mapping is shared. No mutex:
        // another thread of the parent may have held it at the fork.
        int idle = 0;
        if (!shared_->state.compare_exchange_strong(idle, 1)) return;  // one is there already
        const std::string text = InterruptText(e);
        const std::size_t n = std::min(text.size(), sizeof(shared_->text) - 1);
        std::memcpy(shared_->text, text.data(), n);
        shared_->text[n] = '\0';
        shared_->state.store(2);
        return;
    }
    std::lock_guard<std::mutex> guard(mutex_);
    if (error_) return;
    if (!e.matches(PyExc_SystemExit)) {
        error_.emplace(e);
        return;
    }
    // docs/python.md: a SystemExit raised in a callable stops the run like Ctrl-C, raising
    // KeyboardInterrupt; rethrown as itself it left run() as SystemExit, which ends the
    // interpreter unless caught (issue 44). Called with the interpreter lock held.
    PyErr_SetString(PyExc_KeyboardInterrupt, InterruptText(e).c_str());
    error_.emplace();  // fetches the KeyboardInterrupt just set
}

void PendingInterrupt::RethrowIfAny() {
    if (shared_->state.load() == 2) {
        const GilAcquired gil;  // before the mutex, which Store takes with the lock held
        std::lock_guard<std::mutex> guard(mutex_);
        if (!error_) {
            PyErr_SetString(PyExc_KeyboardInterrupt, shared_->text);
            error_.emplace();  // fetches the KeyboardInterrupt just set
        }
        throw *error_;
    }
    std::lock_guard<std::mutex> guard(mutex_);
    if (error_) throw *error_;
}

std::string DescribePythonError(const py::error_already_set& e) {
    const std::string type = py::str(e.type().attr("__name__")).cast<std::string>();
    const std::string text = py::str(e.value()).cast<std::string>();
    return text.empty() ? type : type + ": " + text;
}

namespace {

/// Reads what the callable returned into `r` (lock held). Throws std::runtime_error saying
/// what was wrong with it.
void ReadCallableResult(const py::object& out, AlignResult* r) {
    py::object transform = out;
    if (py::isinstance<py::dict>(out)) {
        const py::dict d = out.cast<py::dict>();
        if (!d.contains("transform")) {
            throw std::runtime_error("returned a dict without a \"transform\" key");
        }
        for (const auto& item : d) {
            const std::string key = py::str(item.first).cast<std::string>();
            const py::handle value = item.second;
            if (key == "transform") {
                transform = py::reinterpret_borrow<py::object>(value);
            } else if (key == "iterations") {
                if (!py::isinstance<py::int_>(value) || py::isinstance<py::bool_>(value)) {
                    throw std::runtime_error("\"iterations\" must be an int");
                }
                r->iterations = value.cast<int>();
            } else if (key == "stop_reason") {
                if (!py::isinstance<py::str>(value)) {
                    throw std::runtime_error("\"stop_reason\" must be a str");
                }
                r->stop_reason = value.cast<std::string>();
            } else {
                // Inside the row and its "extra" object: 2 levels of the row's 64.
                r->extra[key] = PyToJson(value, "returned \"" + key + "\"", /*enclosing=*/2);
            }
        }
    }
    try {
        r->T_target_source = TransformFromPy(transform, "the returned transform");
    } catch (const py::value_error& e) {
        throw std::runtime_error(e.what());
    }
}

}  // namespace

AlignResult CallableMethod::DoAlign(const PointCloud& source, const PointCloud& target,
                                    const AlignContext& /*context*/) {
    const auto start = std::chrono::steady_clock::now();
    const GilAcquired gil;
    const double waited =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    AlignResult r;
    try {
        const py::dict kwargs = JsonToPy(params_);
        const py::object out =
            CallOrPark(fn_, py::make_tuple(CloudToPy(source), CloudToPy(target)), kwargs);
        ReadCallableResult(out, &r);
    } catch (py::error_already_set& e) {
        if (!e.matches(PyExc_Exception)) {
            // KeyboardInterrupt, SystemExit: the run ends (check_interrupt rethrows it).
            pending_->Store(e);
            throw std::runtime_error("interrupted by " + DescribePythonError(e));
        }
        throw std::runtime_error(DescribePythonError(e));
    } catch (const py::builtin_exception& e) {  // a conversion of the result (TypeError, ...)
        throw std::runtime_error(e.what());
    }
    r.extra[kExcludedSecondsKey] = waited;
    return r;
}

ForkHooks InterpreterForkHooks() {
    // The lock state of the forking thread, between prepare and parent.
    static thread_local PyGILState_STATE state;
    ForkHooks hooks;
    hooks.prepare = [] {
        state = PyGILState_Ensure();
        PyOS_BeforeFork();
    };
    hooks.parent = [] {
        PyOS_AfterFork_Parent();
        PyGILState_Release(state);
    };
    hooks.child = [] { PyOS_AfterFork_Child(); };  // the child keeps the lock for its call
    return hooks;
}

}  // namespace regbench::python
