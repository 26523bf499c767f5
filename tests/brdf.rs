//! The network pass's BRDF (`brdf.glsl`, for analytic direct light) against the baker's
//! `Bsdf::eval` on random materials and directions: one BRDF on both sides.

mod common;

use common::{finish_clean, gpu};
use rrf::shaders;
use rrf_baker::glam::Vec3;
use rrf_baker::trace::bsdf::Bsdf;
use rrf_baker::trace::sampling::{Frame, Rng};
use rrf_renderer::backend::compute::{Bind, ComputePass};
use rrf_renderer::backend::sync::{run_passes, Access, Pass, ResourceStates, Use};
use rrf_renderer::{vk, MemoryLocation};

const CASES: usize = 4096;

/// A random unit vector.
fn direction(rng: &mut Rng) -> Vec3 {
    loop {
        let v = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE;
        if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
            return v.normalize();
        }
    }
}

#[test]
fn glsl_brdf_matches_the_bakers() {
    let mut rng = Rng::new(3, 0);
    let mut inputs = Vec::with_capacity(16 * CASES);
    let mut expected = Vec::with_capacity(CASES);
    for i in 0..CASES {
        let base = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        // Every fourth material a plain Lambert (specular 0, not metallic), as the BRDF
        // special-cases it; roughness down to the mirror-like clamp.
        let (metallic, specular) = if i % 4 == 0 { (0.0, 0.0) } else { (rng.next_f32(), rng.next_f32()) };
        let roughness = rng.next_f32().powi(2);
        let (n, wo, wi) = (direction(&mut rng), direction(&mut rng), direction(&mut rng));
        inputs.extend([base.x, base.y, base.z, metallic, roughness, specular, n.x, n.y, n.z]);
        inputs.extend([wo.x, wo.y, wo.z, wi.x, wi.y, wi.z, 0.0]);
        let frame = Frame::new(n);
        expected.push(Bsdf::new(base, metallic, roughness, specular).eval(frame.to_local(wo), frame.to_local(wi)));
    }

    let ctx = gpu();
    let bytes: Vec<u8> = inputs.iter().flat_map(|v| v.to_le_bytes()).collect();
    let cases = ctx.create_buffer_with_data("brdf cases", &bytes, vk::BufferUsageFlags::STORAGE_BUFFER).unwrap();
    let values = ctx
        .create_buffer("brdf values", 16 * CASES as u64, vk::BufferUsageFlags::STORAGE_BUFFER, MemoryLocation::GpuToCpu)
        .unwrap();
    let bindings = [Bind::StorageBuffer(&cases), Bind::StorageBuffer(&values)];
    let pass = ComputePass::new(&ctx, "brdf check", shaders::BRDF_CHECK_COMP, &bindings, 4, (64, 1)).unwrap();
    let count = CASES as u32;
    ctx.submit_once(|cmd| {
        let uses = vec![Use::buffer(&cases, Access::COMPUTE_READ), Use::buffer(&values, Access::COMPUTE_WRITE)];
        let passes = vec![
            Pass::new("brdf", uses, |cmd| pass.record(&ctx, cmd, &count.to_le_bytes(), count, 1)),
            Pass::new("read", vec![Use::buffer(&values, Access::HOST_READ)], |_| {}),
        ];
        run_passes(&ctx, cmd, &mut ResourceStates::default(), passes);
    })
    .unwrap();
    let floats: Vec<f32> =
        values.mapped().unwrap().chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
    let got: Vec<&[f32]> = floats.chunks_exact(4).collect();

    let (mut worst, mut nonzero) = (0.0f32, 0);
    for (i, (g, e)) in got.iter().zip(&expected).enumerate() {
        let g = Vec3::new(g[0], g[1], g[2]);
        // Relative, with a floor for values near zero; GGX near α = 1e-3 is steep, so f32
        // rounding of the half vector moves it by a few 1e-4.
        let error = ((g - *e).abs() / (e.abs() + Vec3::splat(1e-2))).max_element();
        worst = worst.max(error);
        nonzero += usize::from(*e != Vec3::ZERO);
        assert!(error < 2e-3, "case {i}: GPU {g}, baker {e}, inputs {:?}", &inputs[16 * i..16 * i + 16]);
    }
    eprintln!("brdf: {nonzero} of {CASES} cases above both surfaces, worst relative difference {worst:.2e}");
    assert!(nonzero > CASES / 8, "too few cases with light both ways");

    pass.destroy(&ctx);
    ctx.destroy_buffer(cases);
    ctx.destroy_buffer(values);
    finish_clean(ctx);
}
