// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file uninitialized.h
/// Vectors whose resize() leaves trivial elements uninitialised, for large
/// arrays that a parallel loop fills right after: value-initialising them
/// zeroes every page on one thread first, and a fresh page's first touch (the
/// kernel's page fault) is the expensive part of a large allocation
/// (measured: 0.3-1.2 s per GB on one thread on a 2-core virtual machine,
/// about half that from two threads; issue 17).

#include <memory>
#include <new>
#include <utility>
#include <vector>

namespace sss {

/// An allocator that default-initialises (not value-initialises) elements
/// constructed without arguments; everything else as std::allocator.
template <class T, class Base = std::allocator<T>>
class DefaultInitAllocator : public Base {
    using Traits = std::allocator_traits<Base>;

public:
    template <class U>
    struct rebind {
        using other = DefaultInitAllocator<U, typename Traits::template rebind_alloc<U>>;
    };

    using Base::Base;
    DefaultInitAllocator() = default;
    template <class U, class B>
    DefaultInitAllocator(const DefaultInitAllocator<U, B>& other) noexcept
        : Base(static_cast<const B&>(other)) {}

    template <class U>
    void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
        ::new (static_cast<void*>(p)) U;
    }
    template <class U, class... Args>
    void construct(U* p, Args&&... args) {
        Traits::construct(static_cast<Base&>(*this), p, std::forward<Args>(args)...);
    }
};

/// A std::vector whose resize(n) leaves trivial elements uninitialised.
template <class T>
using UninitVector = std::vector<T, DefaultInitAllocator<T>>;

} // namespace sss
