//! `/events`: every event of the run as Server-Sent Events, the same JSON
//! as `mp live --json` prints. A browser that connects late first gets the
//! state so far (each person's enter, latest repetition and leave, the
//! recent repetitions and other events, the last status, the summary), so
//! its page is right whatever moment it opened.
//!
//! Each browser has a bounded queue of its own; the run only ever tries to
//! put a line in it, and a browser whose queue is full (it stopped reading)
//! is disconnected.

use std::collections::{BTreeMap, VecDeque};
use std::io::Write;
use std::sync::mpsc::{sync_channel, Receiver, RecvTimeoutError, SyncSender, TrySendError};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

/// Lines a browser may have waiting before it counts as stuck.
pub const QUEUE_LINES: usize = 512;
/// Browsers that may follow the events at once.
pub const MAX_CLIENTS: usize = 32;
/// Recent repetitions replayed to a late browser.
const RECENT_REPS: usize = 20;
/// Recent events of other types (`segment`, `error`, types this page does
/// not know) replayed to a late browser.
const RECENT_OTHER: usize = 40;
/// Seconds between two comment lines to an idle browser (a closed
/// connection is noticed then).
const KEEP_ALIVE: Duration = Duration::from_secs(10);

type Line = (u64, Arc<str>);

/// What a late browser is sent first.
#[derive(Default)]
struct Replay {
    seq: u64,
    /// Per person: enter, latest repetition, leave.
    people: BTreeMap<u64, [Option<Line>; 3]>,
    reps: VecDeque<Line>,
    other: VecDeque<Line>,
    status: Option<Line>,
    summary: Option<Line>,
}

impl Replay {
    fn add(&mut self, json: Arc<str>, value: &serde_json::Value) {
        self.seq += 1;
        let line = (self.seq, json);
        let person = value.get("person").and_then(serde_json::Value::as_u64);
        let kind = value.get("type").and_then(serde_json::Value::as_str);
        match (kind, person) {
            (Some("enter"), Some(p)) => self.people.entry(p).or_default()[0] = Some(line),
            (Some("rep"), Some(p)) => {
                self.people.entry(p).or_default()[1] = Some(line.clone());
                push_bounded(&mut self.reps, line, RECENT_REPS);
            }
            (Some("leave"), Some(p)) => self.people.entry(p).or_default()[2] = Some(line),
            (Some("status"), _) => self.status = Some(line),
            (Some("summary"), _) => self.summary = Some(line),
            _ => push_bounded(&mut self.other, line, RECENT_OTHER),
        }
    }

    /// Every retained line, in the order they happened.
    fn lines(&self) -> Vec<Arc<str>> {
        let mut all: Vec<&Line> = self
            .people
            .values()
            .flat_map(|p| p.iter().flatten())
            .chain(self.reps.iter())
            .chain(self.other.iter())
            .chain(self.status.iter())
            .chain(self.summary.iter())
            .collect();
        all.sort_by_key(|l| l.0);
        all.dedup_by_key(|l| l.0);
        all.into_iter().map(|l| l.1.clone()).collect()
    }
}

fn push_bounded(q: &mut VecDeque<Line>, line: Line, cap: usize) {
    if q.len() == cap {
        q.pop_front();
    }
    q.push_back(line);
}

#[derive(Default)]
struct Inner {
    replay: Replay,
    clients: Vec<SyncSender<Arc<str>>>,
}

/// The events so far and the browsers that follow them.
#[derive(Default)]
pub struct EventHub {
    inner: Mutex<Inner>,
}

impl EventHub {
    fn lock(&self) -> MutexGuard<'_, Inner> {
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Records an event (its JSON line) and offers it to every browser;
    /// a browser whose queue is full is dropped. Never blocks on a browser.
    pub fn publish(&self, json: String) {
        let value: serde_json::Value = serde_json::from_str(&json).unwrap_or_default();
        let json: Arc<str> = json.into();
        let mut inner = self.lock();
        inner.replay.add(json.clone(), &value);
        inner.clients.retain(|c| match c.try_send(json.clone()) {
            Ok(()) => true,
            Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) => false,
        });
    }

    /// A new browser's queue, holding the state so far; `None` when
    /// [`MAX_CLIENTS`] browsers already follow the events.
    pub fn subscribe(&self) -> Option<Receiver<Arc<str>>> {
        let mut inner = self.lock();
        inner.clients.retain(|c| {
            // A closed browser's receiver is gone: find out without sending.
            !matches!(
                c.try_send(Arc::from("")),
                Err(TrySendError::Disconnected(_))
            )
        });
        if inner.clients.len() >= MAX_CLIENTS {
            return None;
        }
        let lines = inner.replay.lines();
        let (tx, rx) = sync_channel(QUEUE_LINES + lines.len());
        for l in lines {
            // The queue has room for every line of the replay.
            let _ = tx.try_send(l);
        }
        inner.clients.push(tx);
        Some(rx)
    }

    /// Browsers following the events now.
    #[cfg(test)]
    pub fn clients(&self) -> usize {
        self.lock().clients.len()
    }
}

/// Sends one browser its events until it goes, the hub drops it, or
/// `stop` is set. Empty lines in the queue are probes and are skipped.
pub fn serve_client(
    mut out: Box<dyn Write + Send>,
    rx: Receiver<Arc<str>>,
    stop: &std::sync::atomic::AtomicBool,
) {
    let head = "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream; charset=utf-8\r\n\
                Cache-Control: no-cache\r\nConnection: close\r\n\r\nretry: 2000\n\n";
    if out
        .write_all(head.as_bytes())
        .and_then(|()| out.flush())
        .is_err()
    {
        return;
    }
    while !stop.load(std::sync::atomic::Ordering::SeqCst) {
        let sent = match rx.recv_timeout(KEEP_ALIVE) {
            Ok(line) if line.is_empty() => continue,
            Ok(line) => write!(out, "data: {line}\n\n"),
            Err(RecvTimeoutError::Timeout) => out.write_all(b": keep-alive\n\n"),
            Err(RecvTimeoutError::Disconnected) => return,
        };
        if sent.and_then(|()| out.flush()).is_err() {
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn event(hub: &EventHub, json: &str) {
        hub.publish(json.to_string());
    }

    #[test]
    fn a_late_browser_gets_the_state_so_far_in_order() {
        let hub = EventHub::default();
        event(&hub, r#"{"type":"enter","person":1,"t":0.5}"#);
        for n in 1..=30 {
            event(
                &hub,
                &format!(r#"{{"type":"rep","person":1,"count":{n},"start":0,"end":1,"t":{n}}}"#),
            );
            event(&hub, &format!(r#"{{"type":"status","t":{n}}}"#));
        }
        event(
            &hub,
            r#"{"type":"segment","person":1,"index":0,"summary":"x"}"#,
        );
        event(&hub, r#"{"type":"summary","frames":9,"people":[]}"#);
        let rx = hub.subscribe().unwrap();
        let got: Vec<String> = rx.try_iter().map(|l| l.to_string()).collect();
        assert_eq!(got[0], r#"{"type":"enter","person":1,"t":0.5}"#);
        let reps: Vec<&String> = got.iter().filter(|l| l.contains("\"rep\"")).collect();
        assert_eq!(reps.len(), RECENT_REPS);
        assert!(reps.last().unwrap().contains("\"count\":30"));
        let statuses: Vec<&String> = got.iter().filter(|l| l.contains("\"status\"")).collect();
        assert_eq!(statuses, [r#"{"type":"status","t":30}"#]);
        assert!(got[got.len() - 2].contains("segment"));
        assert!(got[got.len() - 1].contains("summary"));
    }

    #[test]
    fn a_browser_that_stops_reading_is_dropped() {
        let hub = EventHub::default();
        let stuck = hub.subscribe().unwrap();
        let reading = hub.subscribe().unwrap();
        for n in 0..QUEUE_LINES + 1 {
            event(&hub, &format!(r#"{{"type":"status","t":{n}}}"#));
            while reading.try_recv().is_ok() {}
        }
        assert_eq!(hub.clients(), 1);
        assert_eq!(stuck.try_iter().count(), QUEUE_LINES);
        drop(reading);
        assert!(hub.subscribe().is_some());
        assert_eq!(hub.clients(), 1);
    }
}
