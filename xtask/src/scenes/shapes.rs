//! Triangle meshes for the generated scenes: quads, boxes, spheres, tori and lathed shapes,
//! with normals facing out and counter-clockwise winding seen from outside.

use std::f32::consts::{PI, TAU};

use glam::{Vec2, Vec3};

#[derive(Default, Clone)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub indices: Vec<u32>,
}

impl Mesh {
    pub fn append(&mut self, other: &Mesh) {
        let base = self.positions.len() as u32;
        self.positions.extend(&other.positions);
        self.normals.extend(&other.normals);
        self.uvs.extend(&other.uvs);
        self.indices.extend(other.indices.iter().map(|i| i + base));
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// A regular grid of `(u, v)` samples, `f` giving position and normal, joined into quads.
    fn grid(nu: u32, nv: u32, f: impl Fn(f32, f32) -> (Vec3, Vec3)) -> Mesh {
        let mut m = Mesh::default();
        for j in 0..=nv {
            for i in 0..=nu {
                let (u, v) = (i as f32 / nu as f32, j as f32 / nv as f32);
                let (p, n) = f(u, v);
                m.positions.push(p);
                m.normals.push(n);
                m.uvs.push(Vec2::new(u, v));
            }
        }
        let row = nu + 1;
        for j in 0..nv {
            for i in 0..nu {
                let (a, b, c, d) = (j * row + i, j * row + i + 1, (j + 1) * row + i + 1, (j + 1) * row + i);
                m.indices.extend([a, b, c, a, c, d]);
            }
        }
        m
    }
}

/// A planar quad `a b c d` (in order around its edge) facing `outward`; UVs span `uv_scale`.
pub fn quad(corners: [Vec3; 4], outward: Vec3, uv_scale: Vec2) -> Mesh {
    let [a, b, c, d] = corners;
    let mut n = (b - a).cross(c - a).normalize();
    let mut order = [a, b, c, d];
    if n.dot(outward) < 0.0 {
        order = [a, d, c, b];
        n = -n;
    }
    Mesh {
        positions: order.to_vec(),
        normals: vec![n; 4],
        uvs: [Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0)]
            .map(|uv| uv * uv_scale)
            .to_vec(),
        indices: vec![0, 1, 2, 0, 2, 3],
    }
}

/// A prism from its bottom outline (4 points, y = `y0`) extruded to `y1`: the Cornell blocks.
pub fn prism(outline: [Vec2; 4], y0: f32, y1: f32) -> Mesh {
    let center2 = outline.iter().copied().sum::<Vec2>() / 4.0;
    let center = Vec3::new(center2.x, 0.5 * (y0 + y1), center2.y);
    let low = outline.map(|p| Vec3::new(p.x, y0, p.y));
    let high = outline.map(|p| Vec3::new(p.x, y1, p.y));
    let mut m = quad(high, Vec3::Y, Vec2::ONE);
    m.append(&quad(low, Vec3::NEG_Y, Vec2::ONE));
    for i in 0..4 {
        let j = (i + 1) % 4;
        let side = [low[i], low[j], high[j], high[i]];
        let mid = side.iter().copied().sum::<Vec3>() / 4.0;
        m.append(&quad(side, mid - center, Vec2::ONE));
    }
    m
}

/// An axis-aligned box.
pub fn cuboid(min: Vec3, max: Vec3) -> Mesh {
    let outline = [Vec2::new(min.x, min.z), Vec2::new(max.x, min.z), Vec2::new(max.x, max.z), Vec2::new(min.x, max.z)];
    prism(outline, min.y, max.y)
}

pub fn sphere(center: Vec3, radius: f32, segments: u32, rings: u32) -> Mesh {
    let mut m = Mesh::grid(segments, rings, |u, v| {
        let (theta, phi) = (v * PI, u * TAU);
        let n = Vec3::new(theta.sin() * phi.cos(), -theta.cos(), -theta.sin() * phi.sin());
        (center + radius * n, n)
    });
    drop_degenerate(&mut m);
    m
}

pub fn torus(center: Vec3, major: f32, minor: f32, segments: u32, rings: u32) -> Mesh {
    Mesh::grid(segments, rings, |u, v| {
        let (phi, theta) = (u * TAU, v * TAU);
        let ring = Vec3::new(phi.cos(), 0.0, -phi.sin());
        let n = ring * theta.cos() + Vec3::Y * theta.sin();
        (center + ring * major + n * minor, n)
    })
}

/// A surface of revolution about the y axis through `center`, from a profile of
/// `(radius, height)` points listed bottom to top, sampled at `rings` heights.
pub fn lathe(center: Vec3, profile: &[(f32, f32)], segments: u32, rings: u32) -> Mesh {
    let last = (profile.len() - 1) as f32;
    let sample = |v: f32| {
        let t = v * last;
        let i = (t.floor() as usize).min(profile.len() - 2);
        let f = t - i as f32;
        let (r0, y0) = profile[i];
        let (r1, y1) = profile[i + 1];
        (Vec2::new(r0 + (r1 - r0) * f, y0 + (y1 - y0) * f), Vec2::new(r1 - r0, y1 - y0))
    };
    let mut m = Mesh::grid(segments, rings, |u, v| {
        let (p, tangent) = sample(v);
        let phi = u * TAU;
        let dir = Vec3::new(phi.cos(), 0.0, -phi.sin());
        // Outward normal in the profile plane: the tangent turned clockwise.
        let n2 = Vec2::new(tangent.y, -tangent.x).normalize_or(Vec2::X);
        (center + dir * p.x + Vec3::Y * p.y, (dir * n2.x + Vec3::Y * n2.y).normalize())
    });
    drop_degenerate(&mut m);
    m
}

/// Removes triangles with two equal corners (at poles and closed lathe ends).
fn drop_degenerate(m: &mut Mesh) {
    let p = &m.positions;
    let keep: Vec<u32> = m
        .indices
        .chunks_exact(3)
        .filter(|t| {
            let [a, b, c] = [p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]];
            (b - a).cross(c - a).length_squared() > 1e-14
        })
        .flatten()
        .copied()
        .collect();
    m.indices = keep;
}
