//! Mesh uploads (`initial.shape: mesh`): OBJ, OFF, STL and glTF, the format picked by
//! the first byte. Any input must give a mesh or an error, never a panic or an abort.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // the glTF reader catches the gltf crate's validation panics itself, which
    // libFuzzer's panic hook would report; an uncaught panic still aborts the run
    std::panic::set_hook(Box::new(|info| eprintln!("panic (maybe caught): {info}")));
    let Some((&format, bytes)) = data.split_first() else { return };
    let name = ["a.obj", "a.off", "a.stl", "a.glb", "a.gltf"][format as usize % 5];
    let _ = shapeflow::jobs::read_mesh_file(name, bytes);
});
