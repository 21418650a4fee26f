//! Large fixed-capacity structures built directly on the heap (host only).
//!
//! The grid, the planners' working memory and the visibility cache hold arrays sized by a
//! const generic: megabytes that must never pass through the stack. They are allocated
//! zero-filled instead. Which types may be built that way is checked by the compiler: only
//! [`Zeroable`] ones, for which all-zero bytes are a valid value (bytemuck's derive refuses a
//! field that is not, such as a reference, a `NonZero` or an enum whose zero is no variant).

use bytemuck::Zeroable;

/// A `T` whose bytes are all zero, allocated on the heap without building it on the stack.
/// Aborts like any allocation when memory is exhausted.
pub(crate) fn boxed_zeroed<T: Zeroable>() -> std::boxed::Box<T> {
    bytemuck::allocation::try_zeroed_box::<T>()
        .unwrap_or_else(|()| std::alloc::handle_alloc_error(std::alloc::Layout::new::<T>()))
}
