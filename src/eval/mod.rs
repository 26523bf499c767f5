//! `rrf eval`: how close the networks come to the path tracer on configurations they never saw.

pub mod configs;
pub mod figure;
pub mod hdr_flip;
pub mod metrics;
pub mod reference_cache;
pub mod report;
pub mod seams;
