// A non-owning reference to a callable: what std::function would be for a call that does not keep it, without
// ever allocating. The callable must outlive the FunctionRef (pass it down, never store it past the call).
#pragma once

#include <memory>
#include <type_traits>
#include <utility>

namespace vkas {

template <class Signature>
class FunctionRef;
template <class R, class... A>
class FunctionRef<R(A...)> {
  public:
    template <class F, class = std::enable_if_t<!std::is_same_v<std::decay_t<F>, FunctionRef> &&
                                                std::is_invocable_r_v<R, F&, A...>>>
    FunctionRef(F&& f) noexcept  // NOLINT: implicit, like std::function
        : object_(const_cast<void*>(static_cast<const void*>(std::addressof(f)))),
          call_([](void* o, A... args) -> R {
              return (*static_cast<std::remove_reference_t<F>*>(o))(std::forward<A>(args)...);
          }) {}

    R operator()(A... args) const { return call_(object_, std::forward<A>(args)...); }

  private:
    void* object_;
    R (*call_)(void*, A...);
};

}  // namespace vkas
