pub mod lm;
pub mod samples;
