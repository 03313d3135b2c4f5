//! The arrays a tree shares between its clones, allocated once at their final size and filled in
//! place: a large part's tree is hundreds of megabytes, and making its arrays as `Vec`s first
//! would copy every byte once more into fresh memory when they become shared.

use std::mem::MaybeUninit;
use std::sync::Arc;

use bytemuck::Zeroable;
use rayon::prelude::*;

/// A slice of `len` zeroed elements, to be filled through [`unshared`] before it is shared.
pub(super) fn zeroed<T: Zeroable + Send + Sync>(len: usize) -> Arc<[T]> {
    from_fn(len, |_| T::zeroed())
}

/// The slice whose element `i` is `element(i)`, computed on all threads.
pub(super) fn from_fn<T: Send + Sync>(
    len: usize,
    element: impl Fn(usize) -> T + Sync + Send,
) -> Arc<[T]> {
    let mut slice: Arc<[MaybeUninit<T>]> = Arc::new_uninit_slice(len);
    let slots = Arc::get_mut(&mut slice).expect("a new slice is not shared");
    slots.par_iter_mut().enumerate().for_each(|(i, slot)| {
        slot.write(element(i));
    });
    // SAFETY: every element was written just above.
    unsafe { slice.assume_init() }
}

/// The elements of a slice not shared yet, to fill.
pub(super) fn unshared<T>(slice: &mut Arc<[T]>) -> &mut [T] {
    Arc::get_mut(slice).expect("the tree's arrays are filled before they are shared")
}
