//! Automatic exposure: the walkthrough reads a frame back now and then and moves the exposure
//! so that the frame's median brightness sits at mid-grey, as a camera's meter does. The
//! median, unlike the mean, is not pulled up by a light source in view; pixels of pure black,
//! where no surface is (the background), are left out.

/// Display-referred luminance the median pixel is brought to: mid-grey (18%).
const TARGET: f32 = 0.18;
/// The share of the measured error one correction removes: small enough that the change,
/// which the display curve bends, does not overshoot and oscillate.
const GAIN: f32 = 0.5;
/// The largest correction in stops, so that a black frame does not throw the exposure far.
const MAX_STEP: f32 = 1.0;
/// The meter reads every `STRIDE`-th pixel; a prime, so that the pixels read do not line up
/// in columns.
const STRIDE: usize = 7;
/// The darkest luminance the meter counts with; a frame darker than that is as dark as it.
const FLOOR: f32 = 1e-4;

/// The exposure change in stops that brings the median pixel of `rgba` (RGBA8, sRGB-encoded,
/// rows `width` pixels long) toward mid-grey, counting the first `columns` of each row only
/// (what the settings panel leaves of the frame).
pub fn correction(rgba: &[u8], width: usize, columns: usize) -> f32 {
    let mut luminance: Vec<f32> = rgba
        .chunks_exact(4)
        .enumerate()
        .filter(|(i, p)| i % width.max(1) < columns && p[..3] != [0, 0, 0])
        .step_by(STRIDE)
        .map(|(_, p)| {
            let [r, g, b] = [p[0], p[1], p[2]].map(|c| srgb_to_linear(f32::from(c) / 255.0));
            0.2126 * r + 0.7152 * g + 0.0722 * b
        })
        .collect();
    if luminance.is_empty() {
        // Nothing but black: as dark as can be.
        return MAX_STEP;
    }
    let middle = luminance.len() / 2;
    let (_, median, _) = luminance.select_nth_unstable_by(middle, f32::total_cmp);
    (GAIN * (TARGET / median.max(FLOOR)).log2()).clamp(-MAX_STEP, MAX_STEP)
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// RGBA8 of `n` grey pixels of sRGB code `v`.
    fn grey(n: usize, v: u8) -> Vec<u8> {
        [v, v, v, 255].repeat(n)
    }

    #[test]
    fn a_frame_at_mid_grey_keeps_its_exposure_and_others_move_toward_it() {
        // sRGB code 118 is 18.1% linear.
        assert!(correction(&grey(64, 118), 8, 8).abs() < 0.01);
        // Code 84 is 8.8%: half as bright, so half of the one stop it lacks.
        assert!((correction(&grey(64, 84), 8, 8) - 0.5 * (0.18f32 / 0.0887).log2()).abs() < 0.01);
        // Far too bright or black: one stop at most.
        assert_eq!(correction(&grey(64, 255), 8, 8), -MAX_STEP);
        assert_eq!(correction(&grey(64, 0), 8, 8), MAX_STEP);
    }

    #[test]
    fn the_median_ignores_a_bright_light_and_a_black_background() {
        let mut frame = grey(400, 118);
        frame.extend(grey(150, 255));
        frame.extend(grey(150, 1));
        frame.extend(grey(600, 0));
        assert!(correction(&frame, 10, 10).abs() < 0.01, "{}", correction(&frame, 10, 10));
    }

    #[test]
    fn only_the_columns_left_of_the_panel_count() {
        // Rows of 8: 2 mid-grey pixels, then 6 dark ones under the panel.
        let row = [grey(2, 118), grey(6, 10)].concat();
        let frame = row.repeat(16);
        assert!(correction(&frame, 8, 2).abs() < 0.01);
        assert!(correction(&frame, 8, 8) > 0.1, "the dark columns count when asked to");
    }
}
