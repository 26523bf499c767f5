//! Ownership of GPU objects while they are being put together.
//!
//! GPU objects are destroyed explicitly, through the context that made them ([`Destroy`]); a
//! resource still alive at [`Context::finish`] is reported as a leak. A constructor that makes
//! several objects holds each in a [`Guard`] until the last step that can fail: an early return
//! drops the guards, which destroy what was made, and success hands the objects over with
//! [`Guard::keep`].

use std::ops::{Deref, DerefMut};

use crate::backend::context::Context;

/// A GPU object that is destroyed through its context. Destroying an object whose handles
/// are null (one only partly made) is fine.
pub trait Destroy {
    fn destroy(self, ctx: &Context);
}

impl<T: Destroy> Destroy for Vec<T> {
    fn destroy(self, ctx: &Context) {
        for item in self {
            item.destroy(ctx);
        }
    }
}

impl<T: Destroy> Destroy for Option<T> {
    fn destroy(self, ctx: &Context) {
        if let Some(item) = self {
            item.destroy(ctx);
        }
    }
}

/// Destroys what it holds when dropped, unless [`Guard::keep`] hands it over.
pub struct Guard<'a, T: Destroy> {
    ctx: &'a Context,
    value: Option<T>,
}

impl<'a, T: Destroy> Guard<'a, T> {
    pub fn new(ctx: &'a Context, value: T) -> Self {
        Guard { ctx, value: Some(value) }
    }

    /// Hands the object over: the guard no longer destroys it.
    pub fn keep(mut self) -> T {
        self.value.take().expect("a guard holds its value until kept or dropped")
    }
}

impl<T: Destroy> Deref for Guard<'_, T> {
    type Target = T;
    fn deref(&self) -> &T {
        self.value.as_ref().expect("a guard holds its value until kept or dropped")
    }
}

impl<T: Destroy> DerefMut for Guard<'_, T> {
    fn deref_mut(&mut self) -> &mut T {
        self.value.as_mut().expect("a guard holds its value until kept or dropped")
    }
}

impl<T: Destroy> Drop for Guard<'_, T> {
    fn drop(&mut self) {
        if let Some(value) = self.value.take() {
            value.destroy(self.ctx);
        }
    }
}

impl Context {
    /// Guards `value` until it is kept: see the module documentation.
    pub fn guard<T: Destroy>(&self, value: T) -> Guard<'_, T> {
        Guard::new(self, value)
    }
}
