// Shared helpers of the mjtouch._core bindings: numpy array types with
// checked dtype / rank / layout, arrays handed back to Python without a copy,
// and the stage error convention (a std::string message -> ValueError).
#ifndef MJTOUCH_PYTHON_CONVERT_H_
#define MJTOUCH_PYTHON_CONVERT_H_

#include <cstddef>
#include <initializer_list>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include "surface/surface.h"

namespace mjtouch::py {

namespace nb = nanobind;

// Inputs: C-contiguous CPU arrays of a fixed rank. nanobind converts other
// float / int dtypes and layouts (a copy); anything else is a TypeError.
template <typename T, size_t Rank>
using In = nb::ndarray<const T, nb::ndim<Rank>, nb::c_contig, nb::device::cpu>;
using F64_1 = In<double, 1>;
using F64_2 = In<double, 2>;
using F32_2 = In<float, 2>;
using I32_1 = In<int, 1>;
using I32_2 = In<int, 2>;

template <typename T>
using Out = nb::ndarray<nb::numpy, T>;

// A numpy array owning `v` (moved, not copied), of the given shape.
template <typename T>
Out<T> ToNumpy(std::vector<T>&& v, std::initializer_list<size_t> shape) {
  size_t count = 1;
  for (size_t s : shape) count *= s;
  if (count != v.size())  // a stage broke its output size: never hand out a short buffer
    throw std::logic_error("mjtouch._core: stage output has " + std::to_string(v.size()) +
                           " values, expected " + std::to_string(count));
  auto* owned = new std::vector<T>(std::move(v));
  nb::capsule owner(owned, [](void* p) noexcept { delete static_cast<std::vector<T>*>(p); });
  return Out<T>(owned->data(), shape.size(), shape.begin(), owner);
}

// Stage errors reach Python as ValueError with the stage's own message.
[[noreturn]] inline void Fail(const std::string& message) {
  throw nb::value_error(message.c_str());
}

inline std::string Shape(const size_t* shape, size_t ndim) {
  std::string s = "(";
  for (size_t k = 0; k < ndim; ++k) s += (k ? ", " : "") + std::to_string(shape[k]);
  return s + (ndim == 1 ? ",)" : ")");
}

template <typename A>
std::string ShapeOf(const A& a) {
  std::vector<size_t> s(a.ndim());
  for (size_t k = 0; k < a.ndim(); ++k) s[k] = a.shape(k);
  return Shape(s.data(), s.size());
}

// ValueError unless `a` is n x n ("name must be a square (n x n) array").
template <typename A>
int SquareSide(const A& a, const char* name) {
  if (a.shape(0) != a.shape(1) || a.shape(0) == 0)
    Fail(std::string(name) + " must be a non-empty square (n x n) array, got shape " + ShapeOf(a));
  return static_cast<int>(a.shape(0));
}

// ValueError unless `a` has exactly the given 2D shape.
template <typename A>
void RequireShape(const A& a, const char* name, size_t rows, size_t cols, const char* why) {
  if (a.shape(0) != rows || a.shape(1) != cols)
    Fail(std::string(name) + " must have shape (" + std::to_string(rows) + ", " +
         std::to_string(cols) + ") " + why + ", got shape " + ShapeOf(a));
}

// The optional shear fields (both or neither, each n x n) as data pointers
// (null when absent).
inline std::pair<const float*, const float*> ShearFields(const std::optional<F32_2>& shear_x_pa,
                                                         const std::optional<F32_2>& shear_y_pa,
                                                         size_t n) {
  if (shear_x_pa.has_value() != shear_y_pa.has_value())
    Fail("give both shear_x_pa and shear_y_pa, or neither");
  if (!shear_x_pa) return {nullptr, nullptr};
  RequireShape(*shear_x_pa, "shear_x_pa", n, n, "(the pressure field's)");
  RequireShape(*shear_y_pa, "shear_y_pa", n, n, "(the pressure field's)");
  return {shear_x_pa->data(), shear_y_pa->data()};
}

// Counter-surfaces from the (nsurface, 20) row encoding of mjtouch.core
// (type, pos 3, mat 9, size 3, half_x, half_y, elevation, max_height) and the
// height field's samples; *prefixes holds the height fields' row integrals
// that the surfaces point into. Errors name the surface and its valid range.
void DecodeSurfaces(const F64_2& surfaces, const F32_2& hfield, std::vector<CounterSurface>* list,
                    std::vector<std::vector<double>>* prefixes);

void BindStages(nb::module_& m);
void BindContact(nb::module_& m);
void BindTangential(nb::module_& m);
void BindLayered(nb::module_& m);
void BindInstance(nb::module_& m);
void BindAttributes(nb::module_& m);

}  // namespace mjtouch::py

#endif  // MJTOUCH_PYTHON_CONVERT_H_
