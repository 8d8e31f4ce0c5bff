//! Job specs: parsed, then prepared (validated, initial mesh built) without inputs.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    if let Ok(spec) = shapeflow::jobs::parse_spec(text) {
        let _ = shapeflow::jobs::prepare(spec, &Default::default());
    }
});
