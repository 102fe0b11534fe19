//! `mp live`: live analysis of a file or of a stream on standard input.

use clap::Args;
use mp_live::{Event, LiveParams, LiveSource};

/// Arguments of `mp live`.
#[derive(Args, Debug)]
pub struct LiveArgs {
    /// A video file, or `-` for a video stream (e.g. MPEG-TS) on standard input.
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
    /// Also report each person's concrete program, segment by segment, as
    /// its segments are committed (`segment` lines).
    #[arg(long)]
    pub segments: bool,
}

/// `mp live SOURCE`.
pub fn live_cmd(a: &LiveArgs) -> anyhow::Result<()> {
    let params = LiveParams {
        realtime: a.realtime,
        duration_s: a.duration,
        stall_timeout_s: a.stall_timeout,
        window_s: a.window,
        program: a.segments,
        ..LiveParams::default()
    };
    let source = LiveSource::parse(&a.source);
    let cancel = crate::progress::ctrl_c_token();
    let json = a.json;
    let mut print = |e: &Event| {
        if json {
            if let Ok(line) = serde_json::to_string(e) {
                println!("{line}");
            }
        } else if let Some(line) = text_line(e) {
            println!("{line}");
        }
    };
    mp_live::run(&source, &params, &cancel, &mut print)
        .map_err(|e| anyhow::anyhow!("live analysis of {}: {e}", source.name()))?;
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
        Event::Error { .. } => return None,
        Event::Summary(s) => {
            let people: Vec<String> = s
                .people
                .iter()
                .map(|p| format!("person {}: {} repetitions", p.id, p.total_repetitions))
                .collect();
            format!(
                "{} frames analysed, {} dropped{}{}",
                s.frames,
                s.dropped,
                if people.is_empty() { "" } else { "; " },
                people.join("; ")
            )
        }
    })
}
