//! Command-line value parsers for the library's choice types. The library parses them with
//! [`FromStr`](std::str::FromStr) and names them with `Display`; these parsers add what clap
//! needs on top: `--help` lists the possible values, and a typo is a usage error naming them.

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};

use inimtrace::io::exr::ExrCompression;
use inimtrace::metrics::SsimConstants;
use inimtrace::render::{BackendChoice, Method};

/// `--backend`: `auto`, `analytic`, `embree`, `bvh`, `brute` (alias `brute-force`).
pub(crate) fn backend() -> impl TypedValueParser<Value = BackendChoice> {
    PossibleValuesParser::new([
        PossibleValue::new("auto").help("Analytic for rectangle-only scenes, else Embree"),
        PossibleValue::new("analytic").help("Exact f64 rectangles (the paper's kind of scene)"),
        PossibleValue::new("embree").help("Intel Embree (triangles)"),
        PossibleValue::new("bvh").help("The pure-Rust BVH (inimtrace's own 4-wide tree, f64 watertight triangle test)"),
        PossibleValue::new("brute").alias("brute-force").help("Every triangle for every ray (small scenes only)"),
    ])
    .map(|s| s.parse::<BackendChoice>().expect("a listed backend parses"))
}

/// `--exr-compression`: the names of [`ExrCompression::name`].
pub(crate) fn exr_compression() -> impl TypedValueParser<Value = ExrCompression> {
    PossibleValuesParser::new([
        PossibleValue::new("none").help("Uncompressed scan lines (largest, fastest)"),
        PossibleValue::new("rle").help("Run-length encoding (lossless; flat areas only)"),
        PossibleValue::new("zips").help("ZIP (deflate) per scan line (lossless)"),
        PossibleValue::new("zip").help("ZIP (deflate) per 16 scan lines (lossless; the default)"),
        PossibleValue::new("piz").help("Wavelet + Huffman (lossless; best on noisy images)"),
        PossibleValue::new("pxr24").help("Rounds f32 samples to 24 bits, then ZIP (lossy for f32)"),
    ])
    .map(|s| s.parse::<ExrCompression>().expect("a listed compression parses"))
}

/// `--ssim`: `wang2004` or `framework-8bit`.
pub(crate) fn ssim_constants() -> impl TypedValueParser<Value = SsimConstants> {
    PossibleValuesParser::new([
        PossibleValue::new("wang2004").help(
            "Wang et al. 2004 with the dynamic range of our data, `L = 1`: `C1 = (0.01)² = 1e-4`, `C2 = (0.03)² = \
             9e-4`. Name `\"wang2004\"`",
        ),
        PossibleValue::new("framework-8bit").help(
            "The constants for 8-bit data, `C1 = (0.01·255)² = 6.5025`, `C2 = (0.03·255)² = 58.5225`, applied to \
             `[0, 1]` data — what the paper's published framework did. These constants dwarf the image statistics \
             and pin SSIM near 0.999 for almost any pair of images; use only to reproduce the paper's numbers. \
             Name `\"framework-8bit\"`",
        ),
    ])
    .map(|s| s.parse::<SsimConstants>().expect("a listed SSIM constant set parses"))
}

/// `--method` on the command line: parses like [`Method`]'s `FromStr` (so a typo is a usage
/// error before any work) and lists `LC`, `PC`, `LA` and `LA<k>` in `--help`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct MethodValueParser;

impl TypedValueParser for MethodValueParser {
    type Value = Method;

    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &std::ffi::OsStr,
    ) -> std::result::Result<Method, clap::Error> {
        let text = value.to_str().unwrap_or_default();
        text.parse::<Method>().map_err(|message| {
            let name = arg.map(|a| a.to_string()).unwrap_or_else(|| "--method".into());
            clap::Error::raw(
                clap::error::ErrorKind::InvalidValue,
                format!("invalid value '{text}' for '{name}': {message}\n"),
            )
            .with_cmd(cmd)
        })
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(
            [
                PossibleValue::new("LC").help("LensletCenter"),
                PossibleValue::new("PC").help("PupilCenter"),
                PossibleValue::new("LA").help("LensletAverage, 5 x 5"),
                PossibleValue::new("LA<k>").help("LensletAverage, k x k with 1 <= k <= 64 (LA3, LA:3)"),
            ]
            .into_iter(),
        ))
    }
}
