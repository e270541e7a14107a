#pragma once
// Taking the interpreter lock back in a thread the interpreter may be finalising under.
//
// When the interpreter finalises, CPython ends a thread that asks for the lock (a daemon thread
// back from a long C++ call) inside PyEval_RestoreThread / PyGILState_Ensure: pthread_exit, a
// forced unwind. Through pybind11's gil_scoped_release destructor (noexcept) that was
// std::terminate (SIGABRT, exit 134), and through pybind11's dispatcher it drops references
// without a thread state (a fatal Python error). Here such a thread is parked instead: it
// sleeps, holding nothing, until the process exits, as CPython 3.14 does itself.
#include <Python.h>
#include <cxxabi.h>
#include <pybind11/pybind11.h>

#include <exception>
#include <optional>
#include <type_traits>

namespace regbench::python {

namespace py = pybind11;

/// Blocks the calling thread until the process exits; it is named "regbench-parked" (its
/// /proc/self/task/TID/comm). Called only where CPython ended the thread.
[[noreturn]] void ParkUntilExit();

/// f() with the interpreter lock released; the lock taken back, or the thread parked when the
/// interpreter finalises meanwhile. Exceptions of f() are rethrown with the lock held.
template <class F>
auto WithoutGil(F&& f) -> decltype(f()) {
    using Result = decltype(f());
    std::optional<std::conditional_t<std::is_void_v<Result>, bool, Result>> result;
    std::exception_ptr error;
    PyThreadState* const state = PyEval_SaveThread();
    try {
        if constexpr (std::is_void_v<Result>) {
            f();
        } else {
            result.emplace(f());
        }
    } catch (abi::__forced_unwind&) {  // this thread is being ended: never swallowed
        throw;
    } catch (...) {
        error = std::current_exception();
    }
    try {
        PyEval_RestoreThread(state);
    } catch (abi::__forced_unwind&) {
        ParkUntilExit();
    }
    if (error) std::rethrow_exception(error);
    if constexpr (!std::is_void_v<Result>) return std::move(*result);
}

/// fn(*args, **kwargs) with the lock held, or the thread parked when Python code in fn, giving
/// the lock up (time.sleep, I/O), is ended by the finalising interpreter on taking it back: no
/// reference is dropped on the way, which pybind11's call operator did without a thread state.
py::object CallOrPark(py::handle fn, const py::tuple& args, const py::dict& kwargs);

/// pybind11's gil_scoped_acquire for a scope, or the thread parked when the interpreter
/// finalises.
class GilAcquired {
public:
    GilAcquired() {
        try {
            gil_.emplace();
        } catch (abi::__forced_unwind&) {
            ParkUntilExit();
        }
    }

private:
    std::optional<py::gil_scoped_acquire> gil_;
};

}  // namespace regbench::python
