//! `mp live`: live analysis of a file or of a stream on standard input.

use std::io::{IsTerminal, Write};

use clap::Args;
use mp_live::{Event, LiveParams, LiveSource};

use crate::live_page::LivePage;
use crate::live_view::LiveView;

/// Arguments of `mp live`.
#[derive(Args, Debug)]
pub struct LiveArgs {
    /// A video file, `-` for a video stream (e.g. MPEG-TS) on standard input,
    /// a camera (`/dev/video0`) or a network stream (`rtsp://…`, `udp://…`,
    /// `srt://…`, `http://…`, `tcp://…`).
    pub source: String,
    /// Print one JSON object per line instead of text.
    #[arg(long)]
    pub json: bool,
    /// Read a file at its own speed, as a camera would deliver it.
    #[arg(long)]
    pub realtime: bool,
    /// Stop after this many seconds of stream time.
    #[arg(long)]
    pub duration: Option<f64>,
    /// Seconds without a frame after which the stream counts as stalled.
    #[arg(long, default_value_t = LiveParams::default().stall_timeout_s)]
    pub stall_timeout: f64,
    /// Seconds of each person's recent motion that are counted.
    #[arg(long, default_value_t = LiveParams::default().window_s)]
    pub window: f64,
    /// Serve a live page (the annotated video, the people and their counts)
    /// while the stream plays, at 127.0.0.1:8000 or at `--serve=ADDR`: a
    /// port (on 127.0.0.1; 0 for a free one) or HOST:PORT (the `=` keeps a
    /// source after `--serve` a source). After the stream ends the page
    /// stays until Ctrl-C.
    #[arg(long, value_name = "ADDR", num_args = 0..=1, require_equals = true,
          default_missing_value = crate::live_page::DEFAULT_ADDR)]
    pub serve: Option<String>,
    /// Also report each person's concrete program, segment by segment, as
    /// its segments are committed (`segment` lines; the page of `--serve`
    /// shows them in any case).
    #[arg(long)]
    pub segments: bool,
    /// When the stream ends (or on Ctrl-C, or after `--duration`), write
    /// the files `mp run` writes into this folder, from the poses of the
    /// whole stream (kept meanwhile in a spool file there): the track, the
    /// programs, `loops.json`, each person's folder, the plots and the
    /// report page (without the video's frames).
    #[arg(long, short = 'o', value_name = "DIR")]
    pub out: Option<std::path::PathBuf>,
    /// How often the pose model runs: `all` (every frame), `auto` (at least
    /// 12 times a second: every 2nd frame of a 30-fps stream) or a number
    /// of poses a second; the people's poses on the frames between are
    /// filled from the motion. Fewer poses keep up with a faster stream.
    #[arg(long, value_name = "N|auto|all", default_value_t = LiveParams::default().analysis.pose.rate.label())]
    pub pose_fps: String,
}

/// `mp live SOURCE`.
pub fn live_cmd(a: &LiveArgs) -> anyhow::Result<()> {
    let mut params = LiveParams {
        realtime: a.realtime,
        duration_s: a.duration,
        stall_timeout_s: a.stall_timeout,
        window_s: a.window,
        // The page shows the program as it grows.
        program: a.segments || a.serve.is_some(),
        out: a.out.clone(),
        ..LiveParams::default()
    };
    params.analysis.pose.rate = mp_pipeline::PoseRate::parse(&a.pose_fps)?;
    let source = LiveSource::parse(&a.source);
    let cancel = crate::progress::ctrl_c_token();
    let json = a.json;
    // A reader that went away (`mp live … | head`) stops the run.
    let stop = cancel.clone();
    // Text on a terminal: a view redrawn in place, then the summary line.
    let mut view = (!json && std::io::stdout().is_terminal()).then(LiveView::default);
    let segments = a.segments;
    let mut print = |e: &Event| {
        if !segments && matches!(e, Event::Segment { .. }) {
            return;
        }
        let mut out = std::io::stdout().lock();
        let written = if let Some(v) = view.as_mut() {
            v.update(e);
            match e {
                Event::Summary(_) => text_line(e).map_or(Ok(()), |l| writeln!(out, "{l}")),
                _ => v.draw(&mut out),
            }
        } else {
            let line = if json {
                serde_json::to_string(e).ok()
            } else {
                text_line(e)
            };
            line.map_or(Ok(()), |l| writeln!(out, "{l}"))
        };
        if written.and_then(|()| out.flush()).is_err() {
            stop.cancel();
        }
    };
    let page = match &a.serve {
        Some(addr) => {
            let page = LivePage::start(crate::live_page::parse_addr(addr)?)?;
            eprintln!("serving the live page at {}", page.url());
            Some(page)
        }
        None => None,
    };
    let result = match &page {
        Some(page) => mp_live::watch(&source, &params, &cancel, &mut page.sink(&mut print)),
        None => mp_live::watch(&source, &params, &cancel, &mut print),
    };
    result.map_err(|e| anyhow::anyhow!("live analysis of {}: {e}", source.name()))?;
    if let Some(page) = page {
        if !cancel.is_cancelled() {
            eprintln!(
                "the stream ended; the page stays at {} until Ctrl-C",
                page.url()
            );
            while !cancel.is_cancelled() {
                std::thread::sleep(std::time::Duration::from_millis(100));
            }
        }
    }
    Ok(())
}

/// One compact line per event (errors go to standard error, from `main`).
fn text_line(e: &Event) -> Option<String> {
    Some(match e {
        Event::Rep {
            person,
            count,
            start,
            end,
            t,
        } => format!("{t:8.2} s  person {person}  repetition {count}  ({start:.2}–{end:.2} s)"),
        Event::Segment {
            person,
            index,
            start,
            end,
            t,
            summary,
            ..
        } => format!(
            "{t:8.2} s  person {person}  segment {index}  ({start:.2}–{end:.2} s)  {summary}"
        ),
        Event::Enter { person, t } => format!("{t:8.2} s  person {person} enters"),
        Event::Leave { person, t } => format!("{t:8.2} s  person {person} leaves"),
        Event::Status {
            t,
            fps,
            dropped,
            delay,
            ..
        } => format!("{t:8.2} s  {fps:.1} fps, {dropped} frames dropped, {delay:.2} s behind"),
        Event::Reconnect { attempt, reason, t } => {
            format!("{t:8.2} s  the source is tried again (attempt {attempt}): {reason}")
        }
        Event::Error { .. } => return None,
        Event::Summary(s) => {
            let people: Vec<String> = s
                .people
                .iter()
                .map(|p| format!("person {}: {} repetitions", p.id, p.total_repetitions))
                .collect();
            format!(
                "{} frames analysed, {} dropped{}{}{}",
                s.frames,
                s.dropped,
                if people.is_empty() { "" } else { "; " },
                people.join("; "),
                s.out
                    .as_ref()
                    .map(|d| format!("; wrote {d}"))
                    .unwrap_or_default()
            )
        }
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        live: super::LiveArgs,
    }

    #[test]
    fn a_source_may_follow_serve_and_an_address_takes_an_equals_sign() {
        let c = Cli::try_parse_from(["mp", "--serve", "squats.mp4"]).unwrap();
        assert_eq!(c.live.source, "squats.mp4");
        assert_eq!(
            c.live.serve.as_deref(),
            Some(crate::live_page::DEFAULT_ADDR)
        );
        let c = Cli::try_parse_from(["mp", "squats.mp4", "--serve=0"]).unwrap();
        assert_eq!(c.live.serve.as_deref(), Some("0"));
        let c = Cli::try_parse_from(["mp", "-"]).unwrap();
        assert_eq!(c.live.serve, None);
        // Without `=` an address is a second source: refused.
        assert!(Cli::try_parse_from(["mp", "squats.mp4", "--serve", "8080"]).is_err());
    }
}
