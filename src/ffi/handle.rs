//! Opaque handles and checked argument conversion: every pointer that comes in from C passes
//! through one of these functions before it is used.
//!
//! A handle is a `Tagged<T>` on the heap, handed to C as a pointer to an opaque type. The tag
//! (first, at offset 0 in every handle kind) says which kind it is; it is cleared when the
//! handle is freed, so a handle of the wrong kind, and often a freed one, is refused with
//! `SNAKEGRID_INVALID_HANDLE` instead of being followed (after libimagequant).

use super::status::{Failure, Status};
use std::ffi::{c_char, CStr};
use std::ptr::NonNull;

/// A handle's storage. `repr(C)` puts the tag first whatever `T` is, so the tag of any handle
/// can be read through a pointer to any other kind.
#[repr(C)]
struct Tagged<T> {
    tag: u64,
    value: T,
}

/// Tag written into a handle when it is freed, in case the memory is read again before reuse.
const FREED: u64 = 0;

/// An opaque C type and what it holds.
pub(crate) trait Handle {
    /// What the handle owns.
    type Inner;
    /// Distinct per kind, never [`FREED`].
    const TAG: u64;
    /// The C type's name, for messages.
    const NAME: &'static str;
}

/// Moves `value` to the heap and returns the pointer C will hold.
pub(crate) fn into_raw<H: Handle>(value: H::Inner) -> *mut H {
    Box::into_raw(Box::new(Tagged { tag: H::TAG, value })).cast()
}

/// Checks that `ptr` is a live handle of kind `H` and returns its tagged storage.
///
/// # Safety
/// `ptr` must be NULL or point to at least 8 readable bytes; for a handle made by [`into_raw`]
/// that has not been freed this holds for any kind.
unsafe fn check<H: Handle>(
    ptr: *const H,
    argument: &str,
) -> Result<NonNull<Tagged<H::Inner>>, Failure> {
    let tagged = NonNull::new(ptr.cast::<Tagged<H::Inner>>().cast_mut())
        .ok_or_else(|| Failure::null(argument))?;
    let tag = tagged.cast::<u64>();
    let refused = || {
        Failure::new(
            Status::INVALID_HANDLE,
            format!("argument {argument} is not a live {} handle", H::NAME),
        )
    };
    // A misaligned pointer cannot be one of ours (Box allocations are aligned); refuse it before
    // reading, since an unaligned read would itself be undefined behaviour.
    if !tag.as_ptr().is_aligned() {
        return Err(refused());
    }
    // SAFETY: non-NULL and aligned; the caller guarantees 8 readable bytes, and every handle
    // kind stores its u64 tag at offset 0.
    if unsafe { tag.read() } != H::TAG {
        return Err(refused());
    }
    Ok(tagged)
}

/// Borrows the contents of a live handle of kind `H`.
///
/// # Safety
/// As [`check`]; in addition no other thread may mutate the handle for `'a` (the header states
/// which functions must not share a handle across threads).
pub(crate) unsafe fn get<'a, H: Handle>(
    ptr: *const H,
    argument: &str,
) -> Result<&'a H::Inner, Failure> {
    // SAFETY: the caller's guarantees are those of `check`.
    let tagged = unsafe { check(ptr, argument) }?;
    // SAFETY: the tag matched, so this is a live `Tagged<H::Inner>` made by `into_raw`; no
    // thread mutates it meanwhile (caller's contract).
    Ok(unsafe { &tagged.as_ref().value })
}

/// Borrows the contents of a live handle of kind `H` mutably.
///
/// # Safety
/// As [`get`], and no other reference to the handle may be in use for `'a`.
pub(crate) unsafe fn get_mut<'a, H: Handle>(
    ptr: *mut H,
    argument: &str,
) -> Result<&'a mut H::Inner, Failure> {
    // SAFETY: the caller's guarantees are those of `check`.
    let mut tagged = unsafe { check(ptr, argument) }?;
    // SAFETY: a live handle (tag matched) that nobody else uses meanwhile (caller's contract).
    Ok(unsafe { &mut tagged.as_mut().value })
}

/// Frees a handle of kind `H`; NULL is accepted and ignored, as `free(NULL)` is.
///
/// # Safety
/// As [`get_mut`]; the pointer must not be used again.
pub(crate) unsafe fn free<H: Handle>(ptr: *mut H, argument: &str) -> Result<(), Failure> {
    if ptr.is_null() {
        return Ok(());
    }
    // SAFETY: the caller's guarantees are those of `check`.
    let mut tagged = unsafe { check(ptr, argument) }?;
    // SAFETY: a live handle made by `into_raw` (tag matched) that nobody else uses: clearing
    // the tag and taking the Box back is the reverse of `into_raw`, done once.
    unsafe {
        tagged.as_mut().tag = FREED;
        drop(Box::from_raw(tagged.as_ptr()));
    }
    Ok(())
}

/// Reads a required NUL-terminated UTF-8 string argument.
///
/// # Safety
/// `ptr` must be NULL or a NUL-terminated string that stays unchanged for `'a`.
pub(crate) unsafe fn text<'a>(ptr: *const c_char, argument: &str) -> Result<&'a str, Failure> {
    // SAFETY: the caller's guarantees are those of `optional_text`.
    unsafe { optional_text(ptr, argument) }?.ok_or_else(|| Failure::null(argument))
}

/// Reads an optional NUL-terminated UTF-8 string argument: NULL gives `None`.
///
/// # Safety
/// As [`text`].
pub(crate) unsafe fn optional_text<'a>(
    ptr: *const c_char,
    argument: &str,
) -> Result<Option<&'a str>, Failure> {
    if ptr.is_null() {
        return Ok(None);
    }
    // SAFETY: non-NULL, and the caller guarantees a NUL-terminated string that outlives 'a.
    let text = unsafe { CStr::from_ptr(ptr) };
    text.to_str().map(Some).map_err(|e| {
        Failure::new(
            Status::INVALID_ARGUMENT,
            format!("argument {argument} is not UTF-8: {e}"),
        )
    })
}

/// Reads an array argument (bytes, numbers).
///
/// # Safety
/// `ptr` must be NULL or valid for reading `len` elements that stay unchanged for `'a`.
pub(crate) unsafe fn slice<'a, T>(
    ptr: *const T,
    len: usize,
    argument: &str,
) -> Result<&'a [T], Failure> {
    if ptr.is_null() {
        return Err(Failure::null(argument));
    }
    // No real buffer is this long: a negative length cast to size_t, most likely. Refused here
    // because a slice that long would itself be undefined behaviour.
    if len > isize::MAX as usize / std::mem::size_of::<T>().max(1) {
        return Err(Failure::new(
            Status::INVALID_ARGUMENT,
            format!("argument {argument}: length {len} is not a buffer length"),
        ));
    }
    if !ptr.is_aligned() {
        return Err(Failure::new(
            Status::INVALID_ARGUMENT,
            format!("argument {argument} is not aligned for its element type"),
        ));
    }
    // SAFETY: non-NULL, aligned, at most isize::MAX bytes, and by the caller's guarantee `len`
    // readable elements that outlive 'a.
    Ok(unsafe { std::slice::from_raw_parts(ptr, len) })
}

/// An out-parameter checked for NULL before the work starts and written only once it has
/// succeeded, so that a failed call leaves the caller's variable untouched.
pub(crate) struct Out<T>(NonNull<T>);

impl<T> Out<T> {
    /// # Safety
    /// `ptr` must be NULL or valid for writing a `T` until [`Out::write`] is called.
    pub(crate) unsafe fn new(ptr: *mut T, argument: &str) -> Result<Out<T>, Failure> {
        NonNull::new(ptr)
            .map(Out)
            .ok_or_else(|| Failure::null(argument))
    }

    /// Writes the result. `T` is plain data (a pointer, a number or a C struct), so the old
    /// value is overwritten without being dropped.
    pub(crate) fn write(self, value: T) {
        // SAFETY: non-NULL and valid for writes (guaranteed when the Out was made); `write`
        // neither reads nor drops what was there, which may be uninitialised.
        unsafe { self.0.as_ptr().write(value) }
    }
}

/// An out-array of `len` elements the caller provides, checked before the work starts and
/// written only once it has succeeded, like [`Out`].
pub(crate) struct OutArray<T> {
    ptr: NonNull<T>,
    len: usize,
}

impl<T> OutArray<T> {
    /// # Safety
    /// `ptr` must be NULL or valid for writing `len` elements of `T` until
    /// [`OutArray::write`] is called.
    pub(crate) unsafe fn new(ptr: *mut T, len: usize, argument: &str) -> Result<Self, Failure> {
        NonNull::new(ptr)
            .map(|ptr| OutArray { ptr, len })
            .ok_or_else(|| Failure::null(argument))
    }

    /// The number of elements the caller provided room for.
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// Writes `values`, which the caller of this function has checked to hold exactly
    /// [`OutArray::len`] elements; the elements are plain data, overwritten without a drop.
    pub(crate) fn write(self, values: impl IntoIterator<Item = T>) {
        for (i, value) in values.into_iter().take(self.len).enumerate() {
            // SAFETY: i < len, and the array is valid for writing `len` elements (guaranteed
            // when the OutArray was made); `write` neither reads nor drops the old value.
            unsafe { self.ptr.as_ptr().add(i).write(value) }
        }
    }
}
