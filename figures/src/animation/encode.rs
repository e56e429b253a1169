//! Frames (RGB pixels) to an animated GIF through the `gif` crate, kept small:
//! one global palette for the whole animation (the figures' colours, their
//! blends with white, and a grey ramp for the text's edges: [`Palette`]), and
//! after the first frame only the rectangle that changed, its unchanged pixels
//! transparent, so that LZW packs them into almost nothing.

use std::{borrow::Cow, collections::HashMap, fs::File, io::BufWriter, path::Path};

use plotters::style::RGBColor;

use crate::error::Error;

/// The palette's index for "unchanged" (transparent) pixels.
const TRANSPARENT: u8 = 255;

/// A fixed palette of at most 255 colours and a cache from RGB to index.
pub struct Palette {
    colors: Vec<[u8; 3]>,
    cache: HashMap<[u8; 3], u8>,
}

impl Palette {
    /// `inks` (exactly, each), their blends with white at 3/4, 1/2 and 1/4 of the
    /// ink, and 17 greys from black to white; at most 255 colours in all (index
    /// 255 is transparent).
    pub fn new(inks: &[RGBColor]) -> Self {
        let mut colors: Vec<[u8; 3]> = (0..=16u16).map(|k| [(k * 255 / 16) as u8; 3]).collect();
        for c in inks {
            for a in [1.0, 0.75, 0.5, 0.25] {
                let mix = |v: u8| (a * f64::from(v) + (1.0 - a) * 255.0).round() as u8;
                let rgb = [mix(c.0), mix(c.1), mix(c.2)];
                if !colors.contains(&rgb) && colors.len() < 255 {
                    colors.push(rgb);
                }
            }
        }
        Self { colors, cache: HashMap::new() }
    }

    /// The palette's index of the colour nearest to `rgb` (squared RGB distance;
    /// the first of equally near).
    pub fn index(&mut self, rgb: [u8; 3]) -> u8 {
        if let Some(i) = self.cache.get(&rgb) {
            return *i;
        }
        let d = |c: &[u8; 3]| (0..3).map(|k| (i32::from(c[k]) - i32::from(rgb[k])).pow(2)).sum::<i32>();
        let i = self.colors.iter().enumerate().min_by_key(|(_, c)| d(c)).map_or(0, |(i, _)| i as u8);
        self.cache.insert(rgb, i);
        i
    }

    /// The palette as the GIF's global colour table: 256 RGB triples (the unused
    /// and transparent entries magenta).
    fn table(&self) -> Vec<u8> {
        (0..256).flat_map(|i| self.colors.get(i).copied().unwrap_or([255, 0, 255])).collect()
    }
}

/// An animated GIF being written: `width` x `height` px, every frame `delay_cs`
/// hundredths of a second, looping forever.
pub struct GifWriter {
    encoder: gif::Encoder<BufWriter<File>>,
    palette: Palette,
    previous: Option<Vec<u8>>,
    size: (u16, u16),
    delay_cs: u16,
    path: std::path::PathBuf,
}

impl GifWriter {
    /// Creates `path` for frames of `size` (px) shown `delay_cs` hundredths of a
    /// second each, coloured from `palette`.
    ///
    /// # Errors
    /// [`Error::Io`] when the file cannot be created; [`Error::Plot`] from the encoder.
    pub fn create(path: &Path, size: (u16, u16), delay_cs: u16, palette: Palette) -> Result<Self, Error> {
        let file = File::create(path).map_err(|source| Error::Io { path: path.to_path_buf(), source })?;
        let err = |e: gif::EncodingError| Error::Plot { path: path.to_path_buf(), message: e.to_string() };
        let mut encoder = gif::Encoder::new(BufWriter::new(file), size.0, size.1, &palette.table()).map_err(err)?;
        encoder.set_repeat(gif::Repeat::Infinite).map_err(err)?;
        Ok(Self { encoder, palette, previous: None, size, delay_cs, path: path.to_path_buf() })
    }

    /// Adds a frame of RGB pixels (row by row, `3 * width * height` bytes): the
    /// first whole, each later one as the rectangle of pixels whose palette index
    /// changed, the unchanged ones in it transparent (disposal: keep).
    ///
    /// # Errors
    /// [`Error::Plot`] when `rgb` has the wrong length or the encoder fails.
    pub fn add(&mut self, rgb: &[u8]) -> Result<(), Error> {
        let (w, h) = (usize::from(self.size.0), usize::from(self.size.1));
        let err = |message: String| Error::Plot { path: self.path.clone(), message };
        if rgb.len() != 3 * w * h {
            return Err(err(format!("a frame of {} bytes, not {}", rgb.len(), 3 * w * h)));
        }
        let indices: Vec<u8> = rgb.chunks_exact(3).map(|p| self.palette.index([p[0], p[1], p[2]])).collect();
        let (left, top, fw, fh, buffer) = match &self.previous {
            None => (0, 0, w, h, indices.clone()),
            Some(prev) => {
                let changed = |k: usize| indices[k] != prev[k];
                let rows: Vec<usize> = (0..h).filter(|y| (0..w).any(|x| changed(y * w + x))).collect();
                let cols: Vec<usize> = (0..w).filter(|x| rows.iter().any(|y| changed(y * w + x))).collect();
                match (rows.first(), rows.last(), cols.first(), cols.last()) {
                    (Some(&y0), Some(&y1), Some(&x0), Some(&x1)) => {
                        let mut buf = Vec::with_capacity((x1 - x0 + 1) * (y1 - y0 + 1));
                        for y in y0..=y1 {
                            for x in x0..=x1 {
                                let k = y * w + x;
                                buf.push(if changed(k) { indices[k] } else { TRANSPARENT });
                            }
                        }
                        (x0, y0, x1 - x0 + 1, y1 - y0 + 1, buf)
                    }
                    // Nothing changed: one transparent pixel keeps the frame's time.
                    _ => (0, 0, 1, 1, vec![TRANSPARENT]),
                }
            }
        };
        let frame = gif::Frame {
            left: left as u16,
            top: top as u16,
            width: fw as u16,
            height: fh as u16,
            delay: self.delay_cs,
            dispose: gif::DisposalMethod::Keep,
            transparent: Some(TRANSPARENT),
            buffer: Cow::Owned(buffer),
            ..gif::Frame::default()
        };
        self.encoder.write_frame(&frame).map_err(|e| err(e.to_string()))?;
        self.previous = Some(indices);
        Ok(())
    }

    /// Ends the file (the GIF's trailer) and flushes it.
    ///
    /// # Errors
    /// [`Error::Io`] when the file cannot be written.
    pub fn finish(self) -> Result<(), Error> {
        use std::io::Write as _;
        let io = |source| Error::Io { path: self.path.clone(), source };
        let mut file = self.encoder.into_inner().map_err(io)?;
        file.flush().map_err(io)
    }

    /// The RGB colour the palette gives `rgb` (what the file shows for it).
    pub fn shown(&mut self, rgb: [u8; 3]) -> [u8; 3] {
        let i = self.palette.index(rgb);
        self.palette.colors[usize::from(i)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inks_are_exact_and_changed_pixels_only_are_written() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.gif");
        let red = RGBColor(213, 94, 0);
        let mut g = GifWriter::create(&path, (4, 3), 4, Palette::new(&[red])).unwrap();
        assert_eq!(g.shown([213, 94, 0]), [213, 94, 0]);
        assert_eq!(g.shown([250, 250, 250]), [255, 255, 255]);
        let mut frame = vec![255u8; 36];
        g.add(&frame).unwrap();
        frame[3 * 5..3 * 6].copy_from_slice(&[213, 94, 0]);
        g.add(&frame).unwrap();
        assert!(g.add(&[0u8; 5]).is_err(), "a frame of the wrong size is refused");
        g.finish().unwrap();
        let mut options = gif::DecodeOptions::new();
        options.set_color_output(gif::ColorOutput::Indexed);
        let mut d = options.read_info(File::open(&path).unwrap()).unwrap();
        let first = d.read_next_frame().unwrap().unwrap().clone();
        assert_eq!((first.width, first.height, first.delay), (4, 3, 4));
        let second = d.read_next_frame().unwrap().unwrap();
        assert_eq!((second.left, second.top, second.width, second.height), (1, 1, 1, 1), "only the changed pixel");
    }
}
