#include "python/gil.hpp"

#include <pthread.h>
#include <unistd.h>

namespace regbench::python {

void ParkUntilExit() {
    ::pthread_setname_np(::pthread_self(), "regbench-parked");
    for (;;) ::pause();
}

py::object CallOrPark(py::handle fn, const py::tuple& args, const py::dict& kwargs) {
    PyObject* out = nullptr;
    try {
        out = PyObject_Call(fn.ptr(), args.ptr(), kwargs.ptr());
    } catch (abi::__forced_unwind&) {
        ParkUntilExit();
    }
    if (out == nullptr) throw py::error_already_set();
    return py::reinterpret_steal<py::object>(out);
}

}  // namespace regbench::python
