//! The paper's band diagram (90 wave vectors, 10 modes, the default mesh): the time a design search pays per
//! design (docs/benchmarks.md).
//!
//! `cargo bench -p metaplate-design --bench band`

use criterion::{Criterion, criterion_group, criterion_main};
use metaplate_core::design::Design;
use metaplate_design::{BandOptions, PAPER_WAVELENGTH_FREQS_HZ, band_diagram};

fn paper_band(c: &mut Criterion) {
    let design = Design::paper();
    let options = BandOptions::default();
    let mut group = c.benchmark_group("design");
    group.sample_size(10);
    group.bench_function("paper_band_90x10", |b| {
        b.iter(|| band_diagram(&design, &options, &PAPER_WAVELENGTH_FREQS_HZ).map(|band| band.slow_branch.top_hz))
    });
    group.finish();
}

criterion_group!(benches, paper_band);
criterion_main!(benches);
