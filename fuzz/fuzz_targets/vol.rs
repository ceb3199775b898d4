//! The `.vol` reader on arbitrary bytes: `Ok` with a consistent grid, or `Err`.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(g) = fgf_io::vol::parse_vol(std::path::Path::new("fuzz.vol"), data) {
        assert_eq!(g.data.len(), g.shape.iter().product::<usize>() * g.channels);
        assert!(g.bbox.iter().all(|v| v.is_finite()));
        assert!(g.data.iter().all(|v| v.is_finite()));
    }
});
