use std::time::Instant;
fn main() {
    let img = inimtrace::raster::RgbImage::filled(2160, 2160, [0.3, 0.5, 0.7]);
    let small = inimtrace::raster::RgbImage::filled(512, 512, [0.3, 0.5, 0.7]);
    let t = Instant::now();
    inimtrace::io::exr::write_rgb(std::path::Path::new("/tmp/t.exr"), &img, None, &[]).unwrap();
    eprintln!("exr big {:?}", t.elapsed());
    let t = Instant::now();
    inimtrace::io::png::write_preview(std::path::Path::new("/tmp/t.png"), &img).unwrap();
    eprintln!("png big {:?}", t.elapsed());
    let t = Instant::now();
    inimtrace::io::exr::write_rgb(std::path::Path::new("/tmp/s.exr"), &small, None, &[]).unwrap();
    eprintln!("exr small {:?}", t.elapsed());
    let t = Instant::now();
    let rows: Vec<(&str, Vec<&inimtrace::raster::RgbImage>)> = (0..4).map(|_| ("Near", vec![&small; 4])).collect();
    inimtrace::io::figure::write_montage(std::path::Path::new("/tmp/f.png"), &rows, &["GT", "LC", "PC", "LA"]).unwrap();
    eprintln!("figure {:?}", t.elapsed());
}
