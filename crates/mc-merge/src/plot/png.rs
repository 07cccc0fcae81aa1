//! PNG copies of the SVG plots, rasterised in Rust by `resvg` (cargo feature `png`, on by
//! default), so that a report can be pasted into slides without another tool.
//!
//! Text needs fonts: the system's fonts are loaded once ([`Rasteriser::new`]) and the SVGs'
//! generic `sans-serif` is mapped to the first of a few common sans-serif families that is
//! installed (DejaVu Sans, Liberation Sans, Noto Sans, FreeSans, Arial), else to the first
//! family found. With no font at all the PNGs are refused with an error that says so, rather
//! than written without their labels.

/// The PNG's pixels per SVG unit: 2 gives 1920 × 1280 for a 960 × 640 plot, sharp on slides.
pub const SCALE: f32 = 2.0;

/// The sans-serif families tried, in order.
const SANS: [&str; 5] = [
    "DejaVu Sans",
    "Liberation Sans",
    "Noto Sans",
    "FreeSans",
    "Arial",
];

/// Renders SVG text to PNG bytes with the system's fonts.
pub struct Rasteriser {
    options: resvg::usvg::Options<'static>,
}

impl Rasteriser {
    /// Loads the system's fonts; fails when there is none (text would not render).
    pub fn new() -> Result<Self, String> {
        let mut options = resvg::usvg::Options::default();
        let db = options.fontdb_mut();
        db.load_system_fonts();
        if db.is_empty() {
            return Err(
                "no fonts found in the system's font directories, so the PNG plots \
                 would have no text: install a font (e.g. `apt-get install fonts-dejavu-core`) \
                 or build mc-merge without the `png` feature (the SVG plots need no fonts here)"
                    .into(),
            );
        }
        let installed = |family: &str| {
            db.faces()
                .any(|f| f.families.iter().any(|(name, _)| name == family))
        };
        let family = SANS
            .iter()
            .find(|f| installed(f))
            .map(|f| f.to_string())
            .or_else(|| {
                db.faces()
                    .find_map(|f| f.families.first().map(|(name, _)| name.clone()))
            })
            .unwrap_or_default();
        db.set_sans_serif_family(family.clone());
        options.font_family = family;
        Ok(Self { options })
    }

    /// The family that `sans-serif` resolves to.
    pub fn sans_serif(&self) -> &str {
        &self.options.font_family
    }

    /// Rasterises `svg` at [`SCALE`] on a white background and returns the PNG bytes.
    pub fn png(&self, svg: &str) -> Result<Vec<u8>, String> {
        let tree = resvg::usvg::Tree::from_str(svg, &self.options).map_err(|e| e.to_string())?;
        let size = tree
            .size()
            .to_int_size()
            .scale_by(SCALE)
            .ok_or("empty plot")?;
        let mut pixmap = resvg::tiny_skia::Pixmap::new(size.width(), size.height())
            .ok_or("plot too large to rasterise")?;
        pixmap.fill(resvg::tiny_skia::Color::WHITE);
        resvg::render(
            &tree,
            resvg::tiny_skia::Transform::from_scale(SCALE, SCALE),
            &mut pixmap.as_mut(),
        );
        // Drawn over opaque white, every pixel is opaque, so the premultiplied RGBA is the
        // colour itself and is written as it is: DEFLATE level 1, every row filtered `Up`.
        // Against tiny-skia's own encoder (level 6, a filter chosen per row), which was most
        // of a merge's time, a 1920 × 1280 plot encodes in about a tenth of the time (about
        // 10 ms instead of 100–140 ms, optimised), for files 1.8 times as large (about 185 kB).
        let mut bytes = Vec::new();
        let mut encoder = png::Encoder::new(&mut bytes, size.width(), size.height());
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_deflate_compression(png::DeflateCompression::Level(1));
        encoder.set_filter(png::Filter::Up);
        let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
        writer
            .write_image_data(pixmap.data())
            .map_err(|e| e.to_string())?;
        writer.finish().map_err(|e| e.to_string())?;
        Ok(bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Dark pixels of a rendered SVG (decoded back with tiny-skia).
    fn dark_pixels(r: &Rasteriser, svg: &str) -> usize {
        let png = r.png(svg).unwrap();
        let pixmap = resvg::tiny_skia::Pixmap::decode_png(&png).unwrap();
        pixmap
            .pixels()
            .iter()
            .filter(|p| p.red() < 128 && p.green() < 128 && p.blue() < 128)
            .count()
    }

    #[test]
    fn text_renders_with_the_system_fonts() {
        let r = Rasteriser::new().expect("fonts on this machine");
        assert!(!r.sans_serif().is_empty());
        let blank = r#"<svg xmlns="http://www.w3.org/2000/svg" width="200" height="40"></svg>"#;
        let text = r#"<svg xmlns="http://www.w3.org/2000/svg" width="200" height="40"><text x="5" y="30" font-family="sans-serif" font-size="24">θ 95 µrad</text></svg>"#;
        assert_eq!(dark_pixels(&r, blank), 0);
        // The glyphs cover a few hundred pixels at 2× (none if the font did not resolve).
        assert!(dark_pixels(&r, text) > 200, "{}", dark_pixels(&r, text));
    }
}
