//! Online mapping (`iscene reconstruct --live`): frames are integrated as they arrive, from a
//! recording replayed at a given rate or from a folder another program is still writing, and the
//! caller refreshes its view of the world from the map at a fixed period.
//!
//! One thread waits for each frame and prepares it (decode, segment, fuse masks) while this one
//! integrates the frames before it in order. When integration falls behind the arrivals, the
//! preparing side drops work in a fixed order: the networks of every other frame first (their
//! frames are fused with the cheap part of the segmentation only, as between `--segment-every`
//! frames). No frame is ever dropped: geometry of every frame is integrated, late if need be.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use rayon::prelude::*;
use serde::Serialize;

use crate::error::{InputError, IsceneError};
use crate::io::Sequence;
use crate::io::sequence::DepthStats;
use crate::panoptic::entities::ClassIds;
use crate::panoptic::mapper::{MapperParams, PanopticMapper};
use crate::panoptic::run::{mapper_frame, prepare_frame};
use crate::segmentation::SegmentationService;

/// When frames arrive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Arrivals {
    /// A recording replayed at `hz` frames per second: frame `k` arrives `k / hz` seconds after
    /// the start.
    Replay { hz: f64 },
    /// A folder that may still grow: a frame arrives when the folder lists it (its depth image
    /// is the last file a writer puts in place). The session ends after `idle` with no new frame.
    Follow { idle: Duration },
}

/// The live session's settings.
#[derive(Clone, Debug)]
pub struct LiveSettings {
    pub arrivals: Arrivals,
    /// The world is refreshed at least this often while frames arrive.
    pub refresh_every: Duration,
    /// Integration may trail the arrivals by this many frames before labels are dropped.
    pub max_backlog: usize,
    /// `--frames start:end:step` over the sequence's frames, applied each time the folder is read.
    pub selection: Option<(usize, Option<usize>, usize)>,
}

/// What a live session measured.
#[derive(Clone, Debug, Default, Serialize)]
pub struct LiveReport {
    pub mode: String,
    pub frames_arrived: usize,
    pub frames_integrated: usize,
    /// Frames whose segmentation networks were skipped because integration was behind.
    pub labels_dropped: usize,
    /// From a frame's arrival to the end of its integration, seconds.
    pub integration_lag_mean_s: f64,
    pub integration_lag_max_s: f64,
    pub refreshes: usize,
    /// From the arrival of the newest frame a refresh saw to the end of that refresh, seconds:
    /// how far the refreshed world trailed the camera.
    pub refresh_lag_max_s: f64,
    pub refresh_seconds_mean: f64,
    /// Longest time between the end of one refresh (or the first arrival) and the end of the
    /// next, seconds.
    pub refresh_interval_max_s: f64,
    /// Depth statistics of the integrated frames, as ingest reports them for a batch run.
    pub depth: DepthStats,
    pub seconds: f64,
}

/// Called with the map so far and the frames it holds; returns when the caller's view is fresh.
pub type Refresh<'a> =
    dyn FnMut(&PanopticMapper, &Sequence, &LiveReport) -> Result<(), IsceneError> + 'a;

struct Prepared {
    arrived: Instant,
    record: crate::io::sequence::FrameRecord,
    frame: crate::io::sequence::Frame,
    segmented: crate::panoptic::mapper::SegmentedFrame,
    depth: DepthStats,
    labels_dropped: bool,
}

/// Opens the sequence folder as it is now, with the selection applied.
fn open_now(dir: &std::path::Path, settings: &LiveSettings) -> Result<Sequence, InputError> {
    let mut sequence = Sequence::open(dir)?;
    if let Some((start, end, step)) = settings.selection {
        sequence.select(start, end, step);
    }
    Ok(sequence)
}

/// The sequence at `dir` as it is now. A followed folder that is not yet a sequence with a frame
/// is waited for until its idle time runs out; the error then says what the folder lacked.
pub fn wait_for_sequence(
    dir: &std::path::Path,
    settings: &LiveSettings,
) -> Result<Sequence, IsceneError> {
    let start = Instant::now();
    loop {
        let failure = match open_now(dir, settings) {
            Ok(sequence) if !sequence.frames.is_empty() => return Ok(sequence),
            Ok(_) => "the --frames selection holds no frame yet".to_string(),
            Err(e) => e.to_string(),
        };
        let idle = match settings.arrivals {
            Arrivals::Follow { idle } if start.elapsed() <= idle => idle,
            Arrivals::Follow { idle } => {
                return Err(InputError::invalid(
                    dir,
                    format!(
                        "no frame arrived within {:.1} s ({failure})",
                        idle.as_secs_f64()
                    ),
                )
                .into());
            }
            Arrivals::Replay { .. } => return Err(InputError::invalid(dir, failure).into()),
        };
        std::thread::sleep(Duration::from_millis(50).min(idle));
    }
}

/// Maps the sequence at `dir` as its frames arrive, starting from its listing `first`. Returns
/// the map, the sequence of the frames integrated (in order) and what the session measured.
pub fn map_live(
    dir: &std::path::Path,
    first: Sequence,
    service: Option<&dyn SegmentationService>,
    params: &MapperParams,
    settings: &LiveSettings,
    refresh: &mut Refresh<'_>,
) -> Result<(PanopticMapper, Sequence, LiveReport), IsceneError> {
    let start = Instant::now();
    let classes = ClassIds::builtin();
    let integrated = AtomicUsize::new(0);
    let mut report = LiveReport {
        mode: match settings.arrivals {
            Arrivals::Replay { hz } => format!("replay at {hz} Hz"),
            Arrivals::Follow { idle } => {
                format!("follow, ending after {:.1} s idle", idle.as_secs_f64())
            }
        },
        ..LiveReport::default()
    };
    let mut seen = Sequence {
        frames: Vec::new(),
        ..first.clone()
    };
    let mut mapper = PanopticMapper::new(params.clone());
    // Frames prepared at once when several have arrived: enough to keep every core busy.
    let batch = 2 * rayon::current_num_threads().max(1);
    let (sender, receiver) =
        std::sync::mpsc::sync_channel::<Result<Prepared, IsceneError>>(settings.max_backlog.max(1));
    let arrived_total = std::thread::scope(|scope| -> Result<usize, IsceneError> {
        let integrated = &integrated;
        let classes = &classes;
        let producer = scope.spawn(move || -> usize {
            let mut sequence = first;
            let mut last_arrival = Instant::now();
            let mut k = 0usize;
            loop {
                // Wait for frame k.
                let arrived = match settings.arrivals {
                    Arrivals::Replay { hz } => {
                        if k >= sequence.frames.len() {
                            return k;
                        }
                        let due = start + Duration::from_secs_f64(k as f64 / hz);
                        if let Some(wait) = due.checked_duration_since(Instant::now()) {
                            std::thread::sleep(wait);
                        }
                        due
                    }
                    Arrivals::Follow { idle } => loop {
                        if k < sequence.frames.len() {
                            break Instant::now();
                        }
                        if last_arrival.elapsed() > idle {
                            return k;
                        }
                        std::thread::sleep(Duration::from_millis(50));
                        match open_now(dir, settings) {
                            Ok(s) if s.frames.len() >= sequence.frames.len() => sequence = s,
                            Ok(_) => {}
                            Err(e) => {
                                let _ = sender.send(Err(e.into()));
                                return k;
                            }
                        }
                    },
                };
                last_arrival = arrived;
                // Every frame that has arrived by now is prepared in one parallel batch (as a
                // batch run does), each stamped with its own arrival.
                let listed = sequence.frames.len();
                let available = match settings.arrivals {
                    Arrivals::Replay { hz } => {
                        ((start.elapsed().as_secs_f64() * hz) as usize + 1).min(listed)
                    }
                    Arrivals::Follow { .. } => listed,
                };
                let end = available.clamp(k + 1, k + batch);
                let backlog = end.saturating_sub(integrated.load(Ordering::Relaxed));
                let prepared: Vec<_> = (k..end)
                    .into_par_iter()
                    .map(|i| {
                        // Behind: the networks of every other frame go first.
                        let wanted =
                            service.is_some() && i.is_multiple_of(params.segment_every.max(1));
                        let labels_dropped =
                            wanted && backlog > settings.max_backlog / 2 && i % 2 == 1;
                        let arrived = match settings.arrivals {
                            Arrivals::Replay { hz } => {
                                start + Duration::from_secs_f64(i as f64 / hz)
                            }
                            Arrivals::Follow { .. } => arrived,
                        };
                        prepare_frame(
                            &sequence,
                            i,
                            service,
                            params,
                            classes,
                            wanted && !labels_dropped,
                        )
                        .map(|(frame, segmented)| Prepared {
                            arrived,
                            record: sequence.frames[i].clone(),
                            depth: DepthStats::of(&frame.depth),
                            frame,
                            segmented,
                            labels_dropped,
                        })
                    })
                    .collect();
                for item in prepared {
                    let failed = item.is_err();
                    if sender.send(item).is_err() || failed {
                        return k + 1;
                    }
                    k += 1;
                }
            }
        });
        // Refreshes are timed from the first frame's arrival.
        let mut last_refresh: Option<Instant> = None;
        let mut lag_sum = 0.0;
        let mut refresh_seconds = 0.0;
        for item in receiver {
            let p = item?;
            mapper.integrate(&mapper_frame(&p.frame), &p.segmented);
            integrated.fetch_add(1, Ordering::Relaxed);
            let lag = p.arrived.elapsed().as_secs_f64();
            lag_sum += lag;
            report.integration_lag_max_s = report.integration_lag_max_s.max(lag);
            report.frames_integrated += 1;
            report.labels_dropped += usize::from(p.labels_dropped);
            report.depth.add(&p.depth);
            report.integration_lag_mean_s = lag_sum / report.frames_integrated as f64;
            seen.frames.push(p.record);
            let since = *last_refresh.get_or_insert(p.arrived);
            if since.elapsed() >= settings.refresh_every {
                let began = Instant::now();
                refresh(&mapper, &seen, &report)?;
                let done = Instant::now();
                report.refreshes += 1;
                refresh_seconds += (done - began).as_secs_f64();
                report.refresh_seconds_mean = refresh_seconds / report.refreshes as f64;
                report.refresh_lag_max_s = report
                    .refresh_lag_max_s
                    .max((done - p.arrived).as_secs_f64());
                report.refresh_interval_max_s = report
                    .refresh_interval_max_s
                    .max((done - since).as_secs_f64());
                last_refresh = Some(done);
            }
        }
        Ok(producer.join().expect("the frame reader does not panic"))
    })?;
    report.frames_arrived = arrived_total;
    if seen.frames.is_empty() {
        return Err(InputError::invalid(dir, "no frame was integrated").into());
    }
    mapper.regularise();
    report.seconds = start.elapsed().as_secs_f64();
    Ok((mapper, seen, report))
}
