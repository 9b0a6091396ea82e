//! Animated GIFs drawn and encoded one frame at a time: each bag's cloth markers are decoded
//! as the animation reaches them, so memory holds one frame per bag whatever the number of
//! frames. Each bag is framed on its own over its picked frames (a first pass over them).

use super::draw::{draw_frame, sheet};
use super::frames::{Frame, Source};
use super::marker::MarkerHead;
use super::options::{Pick, RenderError, RenderOptions, WriteError};
use super::view::{view_of, Extent, View};
use crate::ros::bag::TopicIter;
use std::path::PathBuf;

pub(super) enum GifError {
    Render(RenderError),
    Write(WriteError),
}

impl From<RenderError> for GifError {
    fn from(e: RenderError) -> Self {
        GifError::Render(e)
    }
}

impl From<crate::ros::BagError> for GifError {
    fn from(e: crate::ros::BagError) -> Self {
        GifError::Render(e.into())
    }
}

impl From<::gif::EncodingError> for GifError {
    fn from(e: ::gif::EncodingError) -> Self {
        GifError::Write(e.into())
    }
}

impl From<std::io::Error> for GifError {
    fn from(e: std::io::Error) -> Self {
        GifError::Write(e.into())
    }
}

/// The cloth markers of one bag in the order the animation asks for them (ascending, except
/// for `--at` times out of order, which restart the pass).
struct Cursor<'a> {
    src: &'a Source,
    it: TopicIter<'a, MarkerHead>,
    next: usize,
    held: Option<(usize, u64, MarkerHead)>,
}

impl<'a> Cursor<'a> {
    fn new(src: &'a Source) -> Result<Cursor<'a>, RenderError> {
        Ok(Cursor {
            src,
            it: src.bag.topic("/drape/mesh")?,
            next: 0,
            held: None,
        })
    }

    fn get(&mut self, k: usize) -> Result<(u64, MarkerHead), RenderError> {
        if let Some((i, t, m)) = &self.held {
            if *i == k {
                return Ok((*t, m.clone()));
            }
        }
        if k < self.next {
            self.it = self.src.bag.topic("/drape/mesh")?;
            self.next = 0;
        }
        for r in self.it.by_ref() {
            let (t, m) = r?;
            let i = self.next;
            self.next += 1;
            if i == k {
                self.held = Some((i, t, m.clone()));
                return Ok((t, m));
            }
        }
        Err(RenderError::Empty {
            path: self.src.bag.path().to_path_buf(),
        })
    }
}

/// Frames of each bag the GIF's azimuth is chosen on (about; spread over the drawn ones).
const SAMPLE: usize = 6;

/// Draws `bags` side by side as a looping GIF into `out` (all frames unless picked otherwise).
pub(super) fn render_gif(
    bags: &[PathBuf],
    out: &mut impl std::io::Write,
    o: &RenderOptions,
) -> Result<(), GifError> {
    if o.width == 0 || o.height == 0 || o.width.saturating_mul(o.height) > 16_000_000 {
        return Err(RenderError::TileSize {
            width: o.width,
            height: o.height,
        }
        .into());
    }
    let mut opts = o.clone();
    if opts.pick == Pick::Last {
        opts.pick = Pick::All;
    }
    let sources = bags
        .iter()
        .map(|b| Source::open(b, &opts))
        .collect::<Result<Vec<_>, _>>()?;
    let chosen: Vec<Vec<usize>> = sources.iter().map(|s| s.chosen(&opts.pick)).collect();
    let n = chosen.iter().map(Vec::len).min().unwrap_or(0);
    let mut framing: Vec<View> = Vec::with_capacity(sources.len());
    for (src, ch) in sources.iter().zip(&chosen) {
        let mut unique = ch.clone();
        unique.sort_unstable();
        unique.dedup();
        // The camera frames every drawn frame; the azimuth is chosen on a sample of them.
        let every = unique.len().div_ceil(SAMPLE).max(1);
        let mut e = Extent::new();
        let mut sample: Vec<Frame> = Vec::new();
        let mut seen = 0usize;
        src.markers(&unique, |_, t, m| {
            let f = src.frame(t, &m)?;
            e.add(&f);
            if seen.is_multiple_of(every) {
                sample.push(f);
            }
            seen += 1;
            Ok(())
        })?;
        framing.push(view_of(e.sphere(), &sample, &opts));
    }
    if n == 0 {
        return Err(GifError::Write(WriteError::NoFrames));
    }
    let times = &sources[0].times;
    let period_ns = times
        .windows(2)
        .next()
        .map_or(33_333_333, |w| w[1].saturating_sub(w[0]));
    let stride = match &opts.pick {
        Pick::Spread(k) if *k > 1 => (times.len().saturating_sub(1)) / (k - 1),
        _ => 1,
    }
    .max(1);
    let delay_cs = ((period_ns as f64 * stride as f64) / 1e7).round().max(2.0) as u16;
    let row_opts = RenderOptions {
        columns: Some(bags.len()),
        ..opts.clone()
    };
    let (width, height) = (opts.width * bags.len(), opts.height);
    let (Ok(w), Ok(h)) = (u16::try_from(width), u16::try_from(height)) else {
        return Err(GifError::Write(WriteError::TooLargeForGif {
            width,
            height,
        }));
    };
    let mut cursors = sources
        .iter()
        .map(Cursor::new)
        .collect::<Result<Vec<_>, _>>()?;
    let mut enc = ::gif::Encoder::new(&mut *out, w, h, &[])?;
    enc.set_repeat(::gif::Repeat::Infinite)?;
    for i in 0..n {
        let mut row = Vec::with_capacity(cursors.len());
        for (b, cursor) in cursors.iter_mut().enumerate() {
            let (t, m) = cursor.get(chosen[b][i])?;
            let frame = sources[b].frame(t, &m)?;
            row.push(vec![draw_frame(&frame, &framing[b], &opts)]);
        }
        let img = sheet(&row, &row_opts);
        let mut frame = ::gif::Frame::from_rgb_speed(w, h, &img.rgb, 10);
        frame.delay = delay_cs;
        enc.write_frame(&frame)?;
    }
    let out = enc.into_inner()?;
    out.flush()?;
    Ok(())
}
