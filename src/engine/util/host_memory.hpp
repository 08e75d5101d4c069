// Where the engine's host allocations go. The engine knows no Vulkan types: the API layer wraps the application's
// VkAllocationCallbacks in a std::pmr::memory_resource (api/host_allocator.hpp) and makes it the thread's current
// resource for the duration of a command (ScopedHostMemory), and on the threads that join a deferred operation or
// run a batch while they work for it. Everything the engine allocates for a command (containers, owned temporaries)
// comes from the current resource through HostAllocator, captured when the container is constructed, so a container
// frees into the resource it allocated from even if it outlives the scope. Without a scope the current resource is
// std::pmr::new_delete_resource() (operator new and delete).
#pragma once

#include <cstddef>
#include <map>
#include <memory>
#include <memory_resource>
#include <new>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

namespace vkas {

namespace detail {
inline std::pmr::memory_resource*& currentHostMemorySlot() noexcept {
    thread_local std::pmr::memory_resource* current = nullptr;
    return current;
}
}  // namespace detail

// The thread's current resource (never null).
inline std::pmr::memory_resource* currentHostMemory() noexcept {
    std::pmr::memory_resource* r = detail::currentHostMemorySlot();
    return r ? r : std::pmr::new_delete_resource();
}

// Makes `resource` (null: leave the current one) the thread's current resource until the scope ends.
class ScopedHostMemory {
  public:
    explicit ScopedHostMemory(std::pmr::memory_resource* resource) noexcept : previous_(detail::currentHostMemorySlot()) {
        if (resource) detail::currentHostMemorySlot() = resource;
    }
    ~ScopedHostMemory() { detail::currentHostMemorySlot() = previous_; }
    ScopedHostMemory(const ScopedHostMemory&) = delete;
    ScopedHostMemory& operator=(const ScopedHostMemory&) = delete;

  private:
    std::pmr::memory_resource* previous_;
};

// A standard allocator over the resource current when it was constructed. Copies (and rebinds) share the resource;
// containers keep theirs when copied, moved or swapped (propagation as std::pmr::polymorphic_allocator, except
// that a copy-constructed container takes its source's resource).
template <class T>
class HostAllocator {
  public:
    using value_type = T;
    using propagate_on_container_move_assignment = std::true_type;
    using propagate_on_container_swap = std::true_type;

    HostAllocator() noexcept : resource_(currentHostMemory()) {}
    explicit HostAllocator(std::pmr::memory_resource* resource) noexcept : resource_(resource) {}
    template <class U>
    HostAllocator(const HostAllocator<U>& other) noexcept : resource_(other.resource()) {}

    T* allocate(std::size_t n) {
        if (n > std::size_t(-1) / sizeof(T)) throw std::bad_array_new_length();
        return static_cast<T*>(resource_->allocate(n * sizeof(T), alignof(T)));
    }
    void deallocate(T* p, std::size_t n) noexcept { resource_->deallocate(p, n * sizeof(T), alignof(T)); }

    std::pmr::memory_resource* resource() const noexcept { return resource_; }
    template <class U>
    bool operator==(const HostAllocator<U>& other) const noexcept {
        return resource_ == other.resource() || resource_->is_equal(*other.resource());
    }

  private:
    std::pmr::memory_resource* resource_;
};

template <class T>
using HostVector = std::vector<T, HostAllocator<T>>;
template <class K, class V, class Less = std::less<K>>
using HostMap = std::map<K, V, Less, HostAllocator<std::pair<const K, V>>>;
template <class K, class V, class Hash = std::hash<K>>
using HostUnorderedMap = std::unordered_map<K, V, Hash, std::equal_to<K>, HostAllocator<std::pair<const K, V>>>;
template <class K, class Hash = std::hash<K>>
using HostUnorderedSet = std::unordered_set<K, Hash, std::equal_to<K>, HostAllocator<K>>;

// Destroys and frees an object made by makeHostUnique, into the resource it came from.
template <class T>
struct HostDeleter {
    std::pmr::memory_resource* resource = nullptr;
    void operator()(T* p) const noexcept {
        if (!p) return;
        p->~T();
        resource->deallocate(p, sizeof(T), alignof(T));
    }
};
template <class T>
using HostUnique = std::unique_ptr<T, HostDeleter<T>>;

// A T constructed from args in memory from the current resource.
template <class T, class... Args>
HostUnique<T> makeHostUnique(Args&&... args) {
    std::pmr::memory_resource* r = currentHostMemory();
    void* p = r->allocate(sizeof(T), alignof(T));
    try {
        return HostUnique<T>(new (p) T(std::forward<Args>(args)...), HostDeleter<T>{r});
    } catch (...) {
        r->deallocate(p, sizeof(T), alignof(T));
        throw;
    }
}
// The same, default-initialised (no value-initialisation of trivially constructible members: large scratch).
template <class T>
HostUnique<T> makeHostUniqueForOverwrite() {
    std::pmr::memory_resource* r = currentHostMemory();
    void* p = r->allocate(sizeof(T), alignof(T));
    try {
        return HostUnique<T>(new (p) T, HostDeleter<T>{r});
    } catch (...) {
        r->deallocate(p, sizeof(T), alignof(T));
        throw;
    }
}

// An owning type-erased callable, its target in memory from the current resource at construction (std::function
// may allocate through operator new and has no allocator support).
template <class Signature>
class HostFunction;
template <class R, class... A>
class HostFunction<R(A...)> {
  public:
    HostFunction() = default;
    template <class F, class = std::enable_if_t<!std::is_same_v<std::decay_t<F>, HostFunction>>>
    HostFunction(F&& f) {  // NOLINT: implicit, like std::function
        using D = std::decay_t<F>;
        auto target = makeHostUnique<Model<D>>(std::forward<F>(f));
        resource_ = target.get_deleter().resource;
        target_ = target.release();
    }
    HostFunction(HostFunction&& o) noexcept
        : target_(std::exchange(o.target_, nullptr)), resource_(std::exchange(o.resource_, nullptr)) {}
    HostFunction& operator=(HostFunction&& o) noexcept {
        if (this != &o) {
            reset();
            target_ = std::exchange(o.target_, nullptr);
            resource_ = std::exchange(o.resource_, nullptr);
        }
        return *this;
    }
    HostFunction& operator=(std::nullptr_t) noexcept {
        reset();
        return *this;
    }
    ~HostFunction() { reset(); }

    explicit operator bool() const noexcept { return target_ != nullptr; }
    R operator()(A... args) const { return target_->call(std::forward<A>(args)...); }

  private:
    struct Concept {
        virtual R call(A... args) = 0;
        virtual void destroy(std::pmr::memory_resource* r) noexcept = 0;
        virtual ~Concept() = default;
    };
    template <class F>
    struct Model final : Concept {
        explicit Model(F&& f) : fn(std::move(f)) {}
        explicit Model(const F& f) : fn(f) {}
        R call(A... args) override { return fn(std::forward<A>(args)...); }
        void destroy(std::pmr::memory_resource* r) noexcept override { HostDeleter<Model>{r}(this); }
        F fn;
    };
    void reset() noexcept {
        if (target_) target_->destroy(resource_);
        target_ = nullptr;
        resource_ = nullptr;
    }

    Concept* target_ = nullptr;
    std::pmr::memory_resource* resource_ = nullptr;
};

}  // namespace vkas
