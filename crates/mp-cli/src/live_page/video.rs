//! `/stream.mjpg`: the analysed frames as MJPEG, each confirmed person's
//! skeleton, id and running count drawn on them.
//!
//! The run hands its newest frame to a mailbox of one slot and goes on;
//! one encoder thread takes the newest frame at most [`MAX_FPS`] times a
//! second, only while a browser watches, scales it to at most
//! [`MAX_WIDTH`] pixels wide, draws on it and encodes it as JPEG. Each
//! browser has a thread of its own that sends the newest JPEG and skips
//! those it was too slow for.

use std::collections::{BTreeMap, HashMap};
use std::io::Write;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use mp_geom::Skeleton;
use mp_live::PersonPose;
use mp_pose::Frame;
use mp_pose::{resize_rgb, RgbView};
use mp_report::{draw_pose, SkeletonStyle, View};
use mp_report::{pixmap_to_rgb, rgb_to_pixmap};

/// Frames encoded per second at most.
pub const MAX_FPS: f64 = 15.0;
/// Width of the frames sent, at most (narrower frames keep their size).
pub const MAX_WIDTH: usize = 640;
/// Browsers that may watch the video at once; more are answered 503.
pub const MAX_STREAMS: usize = 8;
/// JPEG quality.
const QUALITY: u8 = 80;
/// While nobody watches, a frame goes to the mailbox at most this often,
/// so that a browser that opens later (even after the stream ended) sees
/// a recent picture at once.
const IDLE_EVERY: Duration = Duration::from_millis(500);
/// The multipart boundary.
const BOUNDARY: &str = "mpframe";

/// An analysed frame waiting to be drawn.
pub struct Shot {
    frame: Arc<Frame>,
    people: Vec<PersonPose>,
    totals: BTreeMap<u32, usize>,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// The mailbox, the newest JPEG and the browsers watching.
#[derive(Default)]
pub struct VideoHub {
    mailbox: Mutex<(u64, Option<Arc<Shot>>)>,
    mail: Condvar,
    jpeg: Mutex<(u64, Option<Arc<Vec<u8>>>)>,
    encoded: Condvar,
    watchers: AtomicUsize,
    last_offer: Mutex<Option<Instant>>,
}

impl VideoHub {
    /// Browsers watching now.
    pub fn watchers(&self) -> usize {
        self.watchers.load(Ordering::SeqCst)
    }

    /// Offers the run's newest frame: copied into the mailbox (replacing
    /// one not drawn yet) while a browser watches, and every
    /// [`IDLE_EVERY`] otherwise. Never waits on the encoder.
    pub fn offer(&self, frame: &Frame, people: &[PersonPose], totals: &BTreeMap<u32, usize>) {
        if self.watchers() == 0 {
            let mut last = lock(&self.last_offer);
            if last.is_some_and(|t| t.elapsed() < IDLE_EVERY) {
                return;
            }
            *last = Some(Instant::now());
        }
        let shot = Arc::new(Shot {
            frame: Arc::new(frame.clone()),
            people: people.to_vec(),
            totals: totals.clone(),
        });
        let mut slot = lock(&self.mailbox);
        slot.0 += 1;
        slot.1 = Some(shot);
        drop(slot);
        self.mail.notify_all();
    }

    /// The encoder: runs until `stop` is set.
    pub fn encode_loop(&self, stop: &AtomicBool) {
        let mut labels = Labels::default();
        let mut done = 0u64;
        let period = Duration::from_secs_f64(1.0 / MAX_FPS);
        let mut last = Instant::now()
            .checked_sub(period)
            .unwrap_or_else(Instant::now);
        while !stop.load(Ordering::SeqCst) {
            let shot = {
                let slot = lock(&self.mailbox);
                let (slot, _) = self
                    .mail
                    .wait_timeout_while(slot, Duration::from_millis(200), |s| {
                        s.0 == done || self.watchers() == 0
                    })
                    .unwrap_or_else(|p| p.into_inner());
                if slot.0 == done || self.watchers() == 0 {
                    continue;
                }
                let wait = period.saturating_sub(last.elapsed());
                if !wait.is_zero() {
                    drop(slot);
                    std::thread::sleep(wait);
                    lock(&self.mailbox).clone()
                } else {
                    slot.clone()
                }
            };
            let (seq, Some(shot)) = shot else { continue };
            done = seq;
            last = Instant::now();
            if let Some(jpeg) = draw_and_encode(&shot, &mut labels) {
                let mut out = lock(&self.jpeg);
                out.0 += 1;
                out.1 = Some(Arc::new(jpeg));
                drop(out);
                self.encoded.notify_all();
            }
        }
    }

    /// Counts a new watcher, or `None` when [`MAX_STREAMS`] already watch.
    pub fn watch(self: &Arc<Self>) -> Option<Watcher> {
        self.watchers
            .fetch_update(Ordering::SeqCst, Ordering::SeqCst, |n| {
                (n < MAX_STREAMS).then_some(n + 1)
            })
            .ok()?;
        // The encoder draws the mailbox's frame for the newcomer.
        let mut slot = lock(&self.mailbox);
        slot.0 += 1;
        drop(slot);
        self.mail.notify_all();
        Some(Watcher(self.clone()))
    }
}

/// A browser watching the video; counted until dropped.
pub struct Watcher(Arc<VideoHub>);

impl Drop for Watcher {
    fn drop(&mut self) {
        self.0.watchers.fetch_sub(1, Ordering::SeqCst);
    }
}

impl Watcher {
    /// Sends the browser the newest JPEG each time there is one, until its
    /// connection fails or `stop` is set.
    pub fn serve(&self, mut out: Box<dyn Write + Send>, stop: &AtomicBool) {
        let head = format!(
            "HTTP/1.1 200 OK\r\nContent-Type: multipart/x-mixed-replace; boundary={BOUNDARY}\r\n\
             Cache-Control: no-cache\r\nConnection: close\r\n\r\n--{BOUNDARY}\r\n"
        );
        if out.write_all(head.as_bytes()).is_err() {
            return;
        }
        let hub = &self.0;
        let mut sent = 0u64;
        while !stop.load(Ordering::SeqCst) {
            let next = {
                let jpeg = lock(&hub.jpeg);
                let (jpeg, _) = hub
                    .encoded
                    .wait_timeout_while(jpeg, Duration::from_millis(500), |j| {
                        j.0 == sent || j.1.is_none()
                    })
                    .unwrap_or_else(|p| p.into_inner());
                jpeg.clone()
            };
            let (seq, Some(bytes)) = next else { continue };
            if seq == sent {
                continue;
            }
            sent = seq;
            // The boundary right after each part: browsers show a part
            // once the boundary that ends it arrives.
            let part = format!(
                "Content-Type: image/jpeg\r\nContent-Length: {}\r\n\r\n",
                bytes.len()
            );
            let ok = out
                .write_all(part.as_bytes())
                .and_then(|()| out.write_all(&bytes))
                .and_then(|()| out.write_all(format!("\r\n--{BOUNDARY}\r\n").as_bytes()))
                .and_then(|()| out.flush());
            if ok.is_err() {
                return;
            }
        }
    }
}

/// Colours of the people's labels, by id.
const PALETTE: [&str; 6] = [
    "#e6194b", "#3cb44b", "#4363d8", "#f58231", "#911eb4", "#008080",
];

/// A rendered label: premultiplied RGBA.
struct Label {
    width: usize,
    height: usize,
    rgba: Vec<u8>,
}

/// Rendered labels (`#3 · 7`), kept while they are in use.
#[derive(Default)]
struct Labels(HashMap<(u32, usize), Option<Label>>);

impl Labels {
    fn get(&mut self, id: u32, count: usize) -> Option<&Label> {
        if self.0.len() > 256 {
            self.0.clear();
        }
        self.0
            .entry((id, count))
            .or_insert_with(|| {
                let colour = PALETTE[id as usize % PALETTE.len()];
                let text = format!("#{id} · {count}");
                let w = 16 + 11 * text.chars().count();
                let svg = format!(
                    r##"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="26"><rect width="{w}" height="26" rx="5" fill="{colour}" fill-opacity="0.85"/><text x="{}" y="19" font-family="sans-serif" font-size="17" font-weight="bold" fill="#fff" text-anchor="middle">{text}</text></svg>"##,
                    w / 2
                );
                let p = mp_report::svg_to_pixmap("label", &svg, 1.0).ok()?;
                Some(Label {
                    width: p.width() as usize,
                    height: p.height() as usize,
                    rgba: p.data().to_vec(),
                })
            })
            .as_ref()
    }
}

/// The shot scaled to at most [`MAX_WIDTH`] wide, every person drawn on
/// it, as JPEG; `None` when the frame is empty or cannot be encoded.
fn draw_and_encode(shot: &Shot, labels: &mut Labels) -> Option<Vec<u8>> {
    let f = &shot.frame;
    if f.width == 0 || f.height == 0 {
        return None;
    }
    let scale = (MAX_WIDTH as f64 / f.width as f64).min(1.0);
    let (w, h) = (
        ((f.width as f64 * scale).round() as usize).max(1),
        ((f.height as f64 * scale).round() as usize).max(1),
    );
    let rgb = if scale < 1.0 {
        resize_rgb(
            RgbView {
                width: f.width,
                height: f.height,
                data: &f.rgb,
            },
            w,
            h,
        )
    } else {
        f.rgb.clone()
    };
    let skeleton = Skeleton::blazepose33();
    let style = SkeletonStyle::for_frame(w, h);
    let poses: Vec<(&PersonPose, Vec<[f64; 2]>)> = shot
        .people
        .iter()
        .map(|p| {
            let kp = p
                .keypoints_px
                .iter()
                .map(|k| [k[0] * scale, k[1] * scale])
                .collect();
            (p, kp)
        })
        .collect();
    // The skeletons with the renderer of the reports and overlay videos,
    // then each person's label over them.
    let mut pixmap = rgb_to_pixmap(&rgb, w, h).ok()?;
    for (p, kp) in &poses {
        if kp.len() == skeleton.joints.len() {
            draw_pose(
                &mut pixmap,
                &skeleton,
                kp,
                &p.visibility,
                &View::frame(1.0),
                &style,
            );
        }
    }
    let mut rgb = pixmap_to_rgb(&pixmap);
    for (p, kp) in &poses {
        let seen: Vec<&[f64; 2]> = kp
            .iter()
            .zip(&p.visibility)
            .filter(|(k, v)| **v > style.min_confidence && k[0].is_finite() && k[1].is_finite())
            .map(|(k, _)| k)
            .collect();
        if seen.is_empty() {
            continue;
        }
        let x = seen.iter().map(|k| k[0]).sum::<f64>() / seen.len() as f64;
        let top = seen.iter().map(|k| k[1]).fold(f64::INFINITY, f64::min);
        let count = shot.totals.get(&p.id).copied().unwrap_or(0);
        if let Some(label) = labels.get(p.id, count) {
            let lx = x - label.width as f64 / 2.0;
            let ly = (top - label.height as f64 - 8.0).max(0.0);
            blend(&mut rgb, w, h, label, lx.round() as i64, ly.round() as i64);
        }
    }
    let mut out = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, QUALITY)
        .encode(&rgb, w as u32, h as u32, image::ExtendedColorType::Rgb8)
        .ok()?;
    Some(out)
}

/// Draws a label over the `w × h` RGB image at `(x, y)`, clipped to it.
fn blend(rgb: &mut [u8], w: usize, h: usize, src: &Label, x: i64, y: i64) {
    let sw = src.width.max(1) as i64;
    for (i, px) in src.rgba.chunks_exact(4).enumerate() {
        let (dx, dy) = (x + i as i64 % sw, y + i as i64 / sw);
        if dx < 0 || dy < 0 || dx >= w as i64 || dy >= h as i64 {
            continue;
        }
        let o = (dy as usize * w + dx as usize) * 3;
        let Some(dst) = rgb.get_mut(o..o + 3) else {
            continue;
        };
        let a = px[3] as u32;
        for (d, s) in dst.iter_mut().zip(&px[..3]) {
            *d = (*s as u32 + *d as u32 * (255 - a) / 255).min(255) as u8;
        }
    }
}
