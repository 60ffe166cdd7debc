use std::path::Path;
use std::time::Instant;
fn main() {
    let img = inimtrace::io::exr::read_rgb(Path::new("out/paper/display_LA.exr")).unwrap();
    for dir in ["/tmp", "out"] {
        let t = Instant::now();
        inimtrace::io::exr::write_rgb(&Path::new(dir).join("t.exr"), &img, None, &[]).unwrap();
        eprintln!("{dir} exr big {:?}", t.elapsed());
        let t = Instant::now();
        inimtrace::io::png::write_preview(&Path::new(dir).join("t.png"), &img).unwrap();
        eprintln!("{dir} png big {:?}", t.elapsed());
    }
}
