// situate.hpp: C++ skills over the C ABI of situate.h (header-only, C++17).
//
// A skill is a class deriving from the `<prefix>::Skill` base that
// `situate gen cpp MANIFEST` writes (it names the typed Inputs, Outputs and
// Params structs and the manifest):
//
//     #include "cpp_runaway.hpp"
//     class Runaway : public cpp_runaway::Skill {
//      public:
//       explicit Runaway(const Params& params);   // optional: else default-constructed
//       void step(const Inputs& in, Outputs& out, const Params& params, situate::Context& cx);
//       void on_param(uint32_t index, const Params& params);   // optional
//       void on_activate(const Params& params, situate::Context& cx);   // optional, or on_activate(cx)
//       void on_deactivate(const Params& params, situate::Context& cx); // optional, or on_deactivate(cx)
//     };
//     SITUATE_CPP_LIBRARY(Runaway)   // once per library; several classes may be listed
//
// `on_activate` is called once when the skill is switched on (at start if it
// starts active, or by the sequencer), before its first `step` after that;
// `on_deactivate` once when it is switched off (by the sequencer or by a
// fault), after its last `step`; both on the thread that runs `step`. Not at
// shutdown: then only the destructor runs.
//
// An exception thrown by the constructor, `step`, `on_param` or
// `on_activate` becomes an error status carrying its `what()`: the skill is
// faulted, the cycle goes on. One thrown by `on_deactivate` is a warning and
// one of the skill's prints (the skill is off anyway).
// Nothing here is a second FFI: the library exports the C ABI.
#pragma once

#include <situate.h>

#include <cstdint>
#include <cstring>
#include <iterator>
#include <exception>
#include <new>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>

namespace situate {

/// What a body sees besides its ports: the cycle, the time, its own prints.
class Context {
 public:
  explicit Context(situate_context* cx) noexcept : cx_(cx) {}

  /// The cycle this body runs in.
  std::uint64_t cycle() const noexcept { return cx_->cycle; }

  /// Seconds since the manager started, on its clock.
  double time_s() const noexcept { return cx_->time_s; }

  /// Adds a line to the skill's own prints.
  void print(std::string_view line) const noexcept {
    if (cx_->host != nullptr && cx_->host->print != nullptr) {
      cx_->host->print(cx_->host_data, line.data(), line.size());
    }
  }

  /// The underlying C context.
  situate_context* raw() const noexcept { return cx_; }

 private:
  situate_context* cx_;
};

/// A string input or parameter as a view (valid during the call).
/// The resources the program provides to a skill, by name, while it is made: a class
/// constructible from `(const Params&, const situate::Resources&)` or
/// `(const situate::Resources&)` gets them. Keep what you take, not this object.
class Resources {
 public:
  explicit Resources(const situate_resources* r) noexcept : r_(r) {}

  /// The resource `name` as a `T*`, or nullptr when the program provides none of that name.
  template <class T = void>
  T* get(std::string_view name) const noexcept {
    if (r_ == nullptr || r_->get == nullptr) return nullptr;
    return static_cast<T*>(r_->get(r_->host_data, name.data(), name.size()));
  }

  /// The resource `name` as a `T&`; throws (the skill is not made, and the robot not built)
  /// when the program provides none of that name.
  template <class T>
  T& need(std::string_view name) const {
    T* found = get<T>(name);
    if (found == nullptr) {
      throw std::runtime_error("needs the resource `" + std::string(name) +
                               "`, and the program provides no C resource of that name");
    }
    return *found;
  }

 private:
  const situate_resources* r_;
};

inline std::string_view view(const situate_str& s) noexcept {
  return s.len == 0 ? std::string_view() : std::string_view(s.ptr, s.len);
}

namespace detail {

inline situate_status fail(situate_error* error, const char* message) noexcept {
  if (error != nullptr) {
    std::strncpy(error->message, message, SITUATE_ERROR_CAPACITY - 1);
    error->message[SITUATE_ERROR_CAPACITY - 1] = '\0';
  }
  return SITUATE_ERROR;
}

// Runs `f`, turning any exception into an error status with its what().
template <class F>
situate_status guarded(situate_error* error, F&& f) noexcept {
  try {
    std::forward<F>(f)();
    return SITUATE_OK;
  } catch (const std::exception& e) {
    return fail(error, e.what());
  } catch (...) {
    return fail(error, "unknown C++ exception");
  }
}

template <class S, class = void>
struct has_on_param : std::false_type {};
template <class S>
struct has_on_param<S, std::void_t<decltype(std::declval<S&>().on_param(std::uint32_t{},
                                                                         std::declval<const typename S::Params&>()))>>
    : std::true_type {};

// on_activate / on_deactivate: with the parameters and the context, or the context only.
template <class S, class = void>
struct has_on_activate_params : std::false_type {};
template <class S>
struct has_on_activate_params<S, std::void_t<decltype(std::declval<S&>().on_activate(
                                     std::declval<const typename S::Params&>(), std::declval<Context&>()))>>
    : std::true_type {};
template <class S, class = void>
struct has_on_activate_cx : std::false_type {};
template <class S>
struct has_on_activate_cx<S, std::void_t<decltype(std::declval<S&>().on_activate(std::declval<Context&>()))>>
    : std::true_type {};
template <class S, class = void>
struct has_on_deactivate_params : std::false_type {};
template <class S>
struct has_on_deactivate_params<S, std::void_t<decltype(std::declval<S&>().on_deactivate(
                                       std::declval<const typename S::Params&>(), std::declval<Context&>()))>>
    : std::true_type {};
template <class S, class = void>
struct has_on_deactivate_cx : std::false_type {};
template <class S>
struct has_on_deactivate_cx<S, std::void_t<decltype(std::declval<S&>().on_deactivate(std::declval<Context&>()))>>
    : std::true_type {};
// A member of that name at all (not overloaded): one of neither form is a mistake, not "no hook".
template <class S, class = void>
struct names_on_activate : std::false_type {};
template <class S>
struct names_on_activate<S, std::void_t<decltype(&S::on_activate)>> : std::true_type {};
template <class S, class = void>
struct names_on_deactivate : std::false_type {};
template <class S>
struct names_on_deactivate<S, std::void_t<decltype(&S::on_deactivate)>> : std::true_type {};

template <class S>
situate_status init(void* state, const void* params, situate_error* error) noexcept {
  using P = typename S::Params;
  return guarded(error, [&] {
    if constexpr (std::is_constructible_v<S, const P&>) {
      new (state) S(*static_cast<const P*>(params));
    } else {
      new (state) S();
    }
  });
}

template <class S>
constexpr bool takes_resources =
    std::is_constructible_v<S, const typename S::Params&, const Resources&> || std::is_constructible_v<S, const Resources&>;

template <class S>
situate_status init_with(void* state, const void* params, const situate_resources* resources,
                         situate_error* error) noexcept {
  using P = typename S::Params;
  return guarded(error, [&] {
    Resources given(resources);
    if constexpr (std::is_constructible_v<S, const P&, const Resources&>) {
      new (state) S(*static_cast<const P*>(params), given);
    } else {
      new (state) S(given);
    }
  });
}

template <class S>
void fini(void* state) noexcept {
  static_cast<S*>(state)->~S();
}

template <class S>
situate_status step(void* state, const void* inputs, void* outputs, const void* params,
                    situate_context* cx) noexcept {
  return guarded(cx->error, [&] {
    Context context(cx);
    static_cast<S*>(state)->step(*static_cast<const typename S::Inputs*>(inputs),
                                 *static_cast<typename S::Outputs*>(outputs),
                                 *static_cast<const typename S::Params*>(params), context);
  });
}

template <class S>
situate_status set_param(void* state, std::uint32_t index, const void* params, situate_error* error) noexcept {
  return guarded(error, [&] {
    static_cast<S*>(state)->on_param(index, *static_cast<const typename S::Params*>(params));
  });
}

template <class S>
situate_status activate(void* state, const void* params, situate_context* cx) noexcept {
  return guarded(cx->error, [&] {
    Context context(cx);
    S& skill = *static_cast<S*>(state);
    if constexpr (has_on_activate_params<S>::value) {
      skill.on_activate(*static_cast<const typename S::Params*>(params), context);
    } else {
      skill.on_activate(context);
    }
  });
}

template <class S>
situate_status deactivate(void* state, const void* params, situate_context* cx) noexcept {
  return guarded(cx->error, [&] {
    Context context(cx);
    S& skill = *static_cast<S*>(state);
    if constexpr (has_on_deactivate_params<S>::value) {
      skill.on_deactivate(*static_cast<const typename S::Params*>(params), context);
    } else {
      skill.on_deactivate(context);
    }
  });
}

}  // namespace detail

/// The C ABI's skill type entry of class `S`.
template <class S>
situate_skill_type skill_type() noexcept {
  static_assert(std::is_standard_layout_v<typename S::Inputs>, "Inputs must be the generated struct");
  constexpr bool activates = detail::has_on_activate_params<S>::value || detail::has_on_activate_cx<S>::value;
  constexpr bool deactivates = detail::has_on_deactivate_params<S>::value || detail::has_on_deactivate_cx<S>::value;
  static_assert(activates || !detail::names_on_activate<S>::value,
                "on_activate must be callable as on_activate(const Params&, situate::Context&) or "
                "on_activate(situate::Context&)");
  static_assert(deactivates || !detail::names_on_deactivate<S>::value,
                "on_deactivate must be callable as on_deactivate(const Params&, situate::Context&) or "
                "on_deactivate(situate::Context&)");
  situate_set_param_fn on_param = nullptr;
  if constexpr (detail::has_on_param<S>::value) {
    on_param = &detail::set_param<S>;
  }
  situate_activate_fn on_activate = nullptr;
  if constexpr (activates) {
    on_activate = &detail::activate<S>;
  }
  situate_deactivate_fn on_deactivate = nullptr;
  if constexpr (deactivates) {
    on_deactivate = &detail::deactivate<S>;
  }
  // Made with the program's resources when its constructor takes them (then `init` is never
  // instantiated: the class may have no other constructor).
  situate_init_fn init = nullptr;
  situate_init_with_fn init_with = nullptr;
  if constexpr (detail::takes_resources<S>) {
    init_with = &detail::init_with<S>;
  } else {
    init = &detail::init<S>;
  }
  return situate_skill_type{S::manifest(),
                            sizeof(typename S::Inputs),
                            sizeof(typename S::Outputs),
                            sizeof(typename S::Params),
                            sizeof(S),
                            alignof(S),
                            init,
                            &detail::fini<S>,
                            &detail::step<S>,
                            on_param,
                            S::inputs_fields(),
                            S::outputs_fields(),
                            S::params_fields(),
                            S::inputs_field_count(),
                            S::outputs_field_count(),
                            S::params_field_count(),
                            on_activate,
                            on_deactivate,
                            init_with};
}

/// The library table of skill classes `S...`.
template <class... S>
const situate_library* library() noexcept {
  static const situate_skill_type types[] = {skill_type<S>()...};
  static const situate_library lib{SITUATE_ABI_VERSION, static_cast<std::uint32_t>(sizeof(situate_skill_type)),
                                   static_cast<std::uint32_t>(sizeof...(S)), types};
  return &lib;
}

}  // namespace situate

/// Exports the library's skill classes: SITUATE_CPP_LIBRARY(A, B). Once per library.
#define SITUATE_CPP_LIBRARY(...)                                                           \
  extern "C" SITUATE_EXPORT const situate_library* situate_library_entry(void) noexcept { \
    return ::situate::library<__VA_ARGS__>();                                              \
  }
