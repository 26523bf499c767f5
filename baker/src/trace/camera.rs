//! A pinhole camera for a [`View`](crate::scene::View).

use glam::{Vec2, Vec3};

use crate::scene::View;

#[derive(Clone, Copy, Debug)]
pub struct Camera {
    pub eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    tan_half_fov: f32,
    aspect: f32,
}

impl Camera {
    /// `aspect` is width / height.
    pub fn new(view: &View, aspect: f32) -> Self {
        let forward = (view.target - view.eye).normalize();
        let right = forward.cross(view.up).normalize_or(Vec3::X);
        let up = right.cross(forward);
        Camera { eye: view.eye, forward, right, up, tan_half_fov: (view.fov_y.to_radians() * 0.5).tan(), aspect }
    }

    /// Direction through the point `film` of the image, in [0, 1]² with (0, 0) at the top left.
    pub fn direction(&self, film: Vec2) -> Vec3 {
        let x = (2.0 * film.x - 1.0) * self.tan_half_fov * self.aspect;
        let y = (1.0 - 2.0 * film.y) * self.tan_half_fov;
        (self.forward + self.right * x + self.up * y).normalize()
    }
}
