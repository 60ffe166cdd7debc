use inimtrace::accel::analytic::AnalyticRects;
use inimtrace::optics::*;
use inimtrace::progress::Progress;
use inimtrace::render::*;
use inimtrace::scene::Scene;
use std::time::Instant;
fn save(path: &str, img: &inimtrace::raster::RgbImage) {
    let mut buf = image::RgbImage::new(img.width as u32, img.height as u32);
    for (i, p) in img.pixels.iter().enumerate() {
        let f = |v: f32| ((v.clamp(0.0, 1.0).powf(1.0 / 2.2)) * 255.0 + 0.5) as u8;
        buf.put_pixel((i % img.width) as u32, (i / img.width) as u32, image::Rgb([f(p[0]), f(p[1]), f(p[2])]));
    }
    buf.save(path).unwrap();
}
fn main() {
    let mut display = Display::paper();
    if let Ok(r) = std::env::var("Q_RES") {
        let r: usize = r.parse().unwrap();
        display.lcd.resolution = [r, r];
    }
    let scene = Scene::paper();
    let backend = AnalyticRects::new(&scene).unwrap();
    let tracer = FacingPlanes::new(&scene, &backend).unwrap();
    let tracer = &tracer;
    let settings = DisplayRenderSettings::default();
    let mut imgs = vec![];
    for m in [Method::LensletCenter, Method::PupilCenter, Method::LensletAverage { grid: 5 }] {
        let t = Instant::now();
        let img = render_display_image(&display, m, &settings, tracer, &Progress::hidden()).unwrap();
        eprintln!("{m}: {:?}", t.elapsed());
        save(&format!("/tmp/q_display_{}.png", m.short_name()), &img);
        imgs.push(img);
    }
    let t = Instant::now();
    let stack = inimtrace::render::retina::DisplayStack::new(&display, &[&imgs[0], &imgs[1], &imgs[2]]).unwrap();
    eprintln!("pack {:?}", t.elapsed());
    let mut retina = Retina::default();
    if let Ok(r) = std::env::var("Q_RET") {
        retina.resolution = r.parse().unwrap();
    }
    for (name, eye) in [
        ("Pin", Eye::pinhole()),
        ("Near", Eye::thin_lens(5.0, Focus::Millimetres(300.0), 8)),
        ("Cen", Eye::thin_lens(5.0, Focus::Millimetres(400.0), 8)),
        ("Far", Eye::thin_lens(5.0, Focus::Millimetres(600.0), 8)),
    ] {
        let t = Instant::now();
        let gt = ground_truth(&eye, &retina, tracer, &Progress::hidden());
        let t1 = t.elapsed();
        let t = Instant::now();
        let sims =
            inimtrace::render::retina::simulate_stack(&display, &eye, &retina, &stack, &Progress::hidden()).unwrap();
        eprintln!("{name}: gt {t1:?} sim {:?}", t.elapsed());
        save(&format!("/tmp/q_gt_{name}.png"), &gt);
        for (s, m) in sims.iter().zip(["LC", "PC", "LA"]) {
            let mse: f64 = (0..3)
                .map(|c| {
                    let a = s.channel(c);
                    let b = gt.channel(c);
                    let mse = a.iter().zip(&b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>() / a.len() as f64;
                    -10.0 * mse.log10()
                })
                .sum::<f64>()
                / 3.0;
            eprintln!("  {m} psnr {mse:.2}");
            save(&format!("/tmp/q_sim_{m}_{name}.png"), s);
        }
    }
}
