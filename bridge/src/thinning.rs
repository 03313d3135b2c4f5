//! Thinning a stream of frames to a rate a remote renderer asks for, never losing the last one.
//!
//! A frame goes out at once when the stream is due; one that comes early is held, replacing any
//! held before it, and goes out when the stream is due again. So a renderer gets at most `hz`
//! frames a second, each as fresh as the rate allows, and always the last state: the server
//! publishes parts only when they move, and a thinned stream that dropped the frame a part came
//! to rest in would show it in flight for good.
//!
//! Frames come in groups that go together: a group is every frame under one frame number (the
//! server publishes each hand's frame under the same number, and a renderer draws a frame's
//! hands together). The first frame of a group decides for the group.

use std::time::{Duration, Instant};

/// One thinned stream of payloads `T`.
#[derive(Debug)]
pub struct Thinner<T> {
    period: Duration,
    /// When the stream may send again; `None` before its first frame.
    due: Option<Instant>,
    /// The group the last frame belonged to, and whether it went out.
    group: Option<(u64, bool)>,
    /// The frames of the latest group that was held.
    held: Vec<T>,
}

impl<T> Thinner<T> {
    /// A stream thinned to `hz` frames a second (`hz` > 0).
    pub fn new(hz: u32) -> Self {
        Self {
            period: Duration::from_secs(1) / hz.max(1),
            due: None,
            group: None,
            held: Vec::new(),
        }
    }

    /// Offers a frame of group `group` at `now`; returns what goes out now.
    pub fn offer(&mut self, now: Instant, group: u64, frame: T) -> Vec<T> {
        match self.group {
            Some((current, true)) if current == group => return vec![frame],
            Some((current, false)) if current == group => {
                self.held.push(frame);
                return Vec::new();
            }
            _ => {}
        }
        if self.due.is_none_or(|due| now >= due) {
            self.advance(now);
            self.group = Some((group, true));
            self.held.clear();
            vec![frame]
        } else {
            self.group = Some((group, false));
            self.held.clear();
            self.held.push(frame);
            Vec::new()
        }
    }

    /// The held frames, if the stream is due at `now`.
    pub fn flush(&mut self, now: Instant) -> Vec<T> {
        match (self.deadline(), &mut self.group) {
            (Some(due), Some((_, sent))) if now >= due => {
                *sent = true;
                self.advance(now);
                std::mem::take(&mut self.held)
            }
            _ => Vec::new(),
        }
    }

    /// When held frames are due to go out; `None` when none are held.
    pub fn deadline(&self) -> Option<Instant> {
        if self.held.is_empty() { None } else { self.due }
    }

    /// The next due time after sending at `now`: one period after the last, so that the rate
    /// is kept on average, or after `now` when the stream was quiet for longer.
    fn advance(&mut self, now: Instant) {
        let next = self.due.map_or(now, |due| due + self.period);
        self.due = Some(if next > now { next } else { now + self.period });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Feeds groups of `size` frames every `interval` for `total`, flushing on time; returns
    /// when each group went out and the group's frames.
    fn run(hz: u32, interval: Duration, total: Duration, size: u64) -> Vec<(Duration, Vec<u64>)> {
        let start = Instant::now();
        let mut thinner = Thinner::new(hz);
        let mut sent: Vec<(Duration, Vec<u64>)> = Vec::new();
        let mut emit = |at: Instant, frames: Vec<u64>| {
            if !frames.is_empty() {
                sent.push((at - start, frames));
            }
        };
        let mut at = start;
        let mut group = 0;
        while at - start < total {
            group += 1;
            // Held frames due before this group arrives go out first.
            while let Some(due) = thinner.deadline().filter(|&due| due <= at) {
                let out = thinner.flush(due);
                emit(due, out);
            }
            for member in 0..size {
                let out = thinner.offer(at, group, group * 10 + member);
                emit(at, out);
            }
            at += interval;
        }
        while let Some(due) = thinner.deadline() {
            let out = thinner.flush(due);
            emit(due, out);
        }
        sent
    }

    #[test]
    fn a_faster_stream_goes_out_at_the_rate_asked_and_ends_with_its_last_frame() {
        // 1 s of frames at 250 Hz, thinned to 90 Hz.
        let sent = run(90, Duration::from_millis(4), Duration::from_secs(1), 1);
        let count = sent.len();
        assert!(
            (89..=91).contains(&count),
            "{count} frames in a second at 90 Hz"
        );
        let period = Duration::from_secs(1) / 90;
        for pair in sent.windows(2) {
            assert!(pair[1].0 - pair[0].0 >= period - Duration::from_micros(1));
        }
        assert_eq!(
            sent.last().map(|(_, frames)| frames.clone()),
            Some(vec![2500])
        );
    }

    #[test]
    fn a_slower_stream_goes_out_whole_and_at_once() {
        let sent = run(90, Duration::from_millis(50), Duration::from_secs(1), 1);
        assert_eq!(sent.len(), 20);
        for (index, (at, frames)) in sent.iter().enumerate() {
            let group = index as u64 + 1;
            assert_eq!(*at, Duration::from_millis(50) * index as u32);
            assert_eq!(frames, &vec![group * 10]);
        }
    }

    #[test]
    fn a_group_goes_out_together_or_not_at_all() {
        let sent = run(30, Duration::from_millis(10), Duration::from_millis(500), 2);
        let mut groups = Vec::new();
        for (_, frames) in &sent {
            groups.extend(frames.iter().map(|frame| frame / 10));
        }
        let mut whole = groups.clone();
        whole.dedup();
        for group in whole {
            let members = groups.iter().filter(|&&g| g == group).count();
            assert_eq!(members, 2, "group {group} went out whole");
        }
        assert_eq!(groups.last(), Some(&50), "the last group went out");
    }
}
