//! `sil-host simulate`: an open-loop run (`u = 0`) of the arm on the belt.
//!
//! Writes under `--out`: `trace.csv` (one row per `--sample-dt`), `events.csv`
//! (every event at its located time), `trace.svg` (`z_t`, `z_n`, `f_n` and the
//! contact mode against time), `trace.html` (the arm animated on the belt beside
//! the trace's plots: [`::figures::trace_page`]) and `summary.json`; with `--format arrow` the two
//! tables are `trace.arrow` and `events.arrow` (Arrow IPC, the same columns), with
//! `--format mcap` both are in `trace.mcap` (channels `/state`, `/contact`,
//! `/events`; [`tables::mcap`]). If the simulation fails part
//! way, everything up to the failure is still written (with the error in the
//! summary) and the command exits with code 1.

use std::time::Instant;

use crate::commands::Done;
use crate::{
    cli::SimulateArgs,
    error::CliError,
    output::{OutputSet, progress_bar},
    table_out::TablesOut,
};
use ::figures::trace_page::{PageInfo, TracePage};
use plant::SimError;

pub mod figures;
mod print;
pub use experiments::simulate::{
    OpenLoop, Prepared, check_times, chosen_initial_condition, parse_x0_deg, prepare, sample_step, summary, summary::*, trace_row,
};
use figures::*;
use print::*;

/// Runs `sil-host simulate`.
///
/// # Errors
/// [`CliError::BadInput`] or an analysis's bad input, parameter or initial state
/// ([`CliError::Analysis`], exit 2) for bad options or initial conditions, before anything is written; [`CliError::Analysis`]
/// (exit 1) when the simulation fails part way (outputs up to then are written);
/// [`CliError::Io`]/[`CliError::Plot`] when writing fails.
pub fn execute(args: &SimulateArgs) -> Result<Done<Summary>, CliError> {
    // Validate everything before touching the output folder.
    crate::features::require_format(args.format)?;
    let prepared = prepare(args)?;
    let (params, sim, initial_condition) = (prepared.params, prepared.sim, prepared.initial_condition.clone());
    let steps = prepared.steps;

    // Before anything is written: an address in use is refused with nothing written.
    let mut live = crate::live::LiveSimulation::start(&args.live, &params)?;
    let mut out = OutputSet::new(&args.output.out)?;
    let progress = progress_bar(steps as u64, "simulating", "samples", args.output.json);
    // Streamed: rows and events go to their files as they come, the figure keeps
    // a decimated copy; nothing grows with the run but the files. CSV rows are
    // formatted and written by a thread of their own (CsvThread) while the
    // simulation goes on; Arrow rows are batched (ArrowFile); MCAP rows and
    // events go into one file, interleaved by time (McapFile).
    #[cfg(feature = "formats")]
    let views = (
        Some(Box::new(arm_view::ArmView::new(arm_view::ArmGeometry::of(&params))) as Box<dyn tables::mcap::McapView<TraceRow>>),
        Some(Box::new(arm_view::EventLog::default()) as Box<dyn tables::mcap::McapView<EventRow>>),
    );
    #[cfg(not(feature = "formats"))]
    let views = (std::marker::PhantomData, std::marker::PhantomData);
    let mut tables = TablesOut::<TraceRow, EventRow>::create(&mut out, ["trace", "events"], args.format, views)?;
    let mut curves = TraceCurves::default();
    let impact_law = format!("{:?}", sim.impact_law).to_lowercase();
    let mut page = (!args.no_page).then(|| TracePage::new(PageInfo::open_loop(&params, &initial_condition.name, &impact_law, sim.e_n)));
    let (mut open_loop, row, startup) = OpenLoop::start(prepared, args.sample_dt);
    let mut n_events = startup.len();
    curves.push_events(&startup);
    curves.push(&row);
    if let Some(page) = &mut page {
        startup.iter().for_each(|e| page.event(e.into()));
        page.push(&(&row).into());
    }
    if let Some(live) = live.as_mut() {
        live.push(std::slice::from_ref(&row), &startup);
    }
    tables.send(vec![row], startup)?;
    // The figure's and the page's copies of the rows (their envelopes, about 0.27 G
    // instructions of the 300 s bouncing run, issue 56) are kept by a thread of
    // their own, fed a copy of each chunk: the same rows in the same order.
    let (to_figures, chunks) = std::sync::mpsc::sync_channel::<(Vec<TraceRow>, Vec<EventRow>)>(4);
    let figures = std::thread::Builder::new()
        .name("simulate-figures".into())
        .spawn(move || {
            for (rows, events) in chunks {
                curves.push_events(&events);
                if let Some(page) = &mut page {
                    events.iter().for_each(|e| page.event(e.into()));
                }
                for row in &rows {
                    curves.push(row);
                    if let Some(page) = &mut page {
                        page.push(&row.into());
                    }
                }
            }
            (curves, page)
        })
        .map_err(|source| CliError::Io { path: out.path("trace.svg"), source })?;
    // The simulation's own wall time, without writing files: rows wait in a
    // chunk of OpenLoop::CHUNK_S s of samples (bounded memory) while the clock runs.
    let mut rows: Vec<TraceRow> = Vec::new();
    let mut new_events: Vec<EventRow> = Vec::new();
    let mut wall = std::time::Duration::ZERO;
    let mut failure: Option<SimError> = None;
    // Ctrl-C or SIGTERM: stop at the next chunk, write what was simulated.
    let stop = crate::cancel::stop_flag();
    let mut stopped = false;
    while !open_loop.finished() && failure.is_none() {
        if stop.load(std::sync::atomic::Ordering::Relaxed) {
            stopped = true;
            break;
        }
        let started = Instant::now();
        failure = open_loop.advance(open_loop.k + 1, &mut rows, &mut new_events).err();
        wall += started.elapsed();
        n_events += new_events.len();
        // A figures thread that panicked is reported when joined, below.
        let _ = to_figures.send((rows.clone(), new_events.clone()));
        if let Some(live) = live.as_mut() {
            live.push(&rows, &new_events);
        }
        (rows, new_events) = tables.send(rows, new_events)?;
        progress.set_position(open_loop.k as u64);
    }
    let plant = open_loop.plant;
    let wall_s = wall.as_secs_f64();
    // The viewers are told while the outputs are written (docs/rig.md "Live").
    let closing = live.map(crate::live::LiveSimulation::close);
    progress.finish_and_clear();
    drop(to_figures);
    let (curves, page) = joined(figures.join());
    // trace.svg (and its PDF) and trace.html's text each on a thread of their own
    // while the tables' writers finish (issue 56: 0.43 G and 0.23 G instructions
    // of the 300 s bouncing run, after the simulation, off its critical path).
    let svg = out.stage_figure("trace.svg")?;
    let (written, drawn, html) = std::thread::scope(|scope| {
        let figure = scope.spawn(|| draw_trace(&svg, &params, &initial_condition.name, &curves));
        let html = page.map(|page| scope.spawn(move || page.html()));
        let written = tables.finish();
        (written, joined(figure.join()), html.map(|h| joined(h.join())))
    });
    written?;
    drawn?;
    if let Some(html) = html {
        out.write_bytes(::figures::trace_page::FILE, html.as_bytes())?;
    }

    let tables = TablesOut::<TraceRow, EventRow>::files(["trace", "events"], args.format);
    let files = tables
        .iter()
        .map(String::as_str)
        .chain(["trace.svg"])
        .chain(::figures::plot::print::WRITES_PDF.then_some("trace.pdf"))
        .chain((!args.no_page).then_some(::figures::trace_page::FILE))
        .chain(["summary.json"])
        .map(|f| out.path(f).display().to_string())
        .collect();
    let mut summary = summary(args, (params, sim, initial_condition), &plant, failure.as_ref(), wall_s, files, n_events);
    let interrupted = stopped.then(|| {
        format!("simulate stopped by a signal at t = {} s of {} s; the outputs up to then are written", summary.simulated_s, args.duration)
    });
    if let Some(why) = &interrupted {
        summary.status = "stopped";
        summary.error = Some(why.clone());
    }
    out.write_json("summary.json", &summary)?;
    let files = out.commit()?;
    if let Some(closing) = closing {
        closing.finish();
    }
    let validity = summary.validity;
    let failure = failure.map(CliError::from).or(interrupted.map(CliError::interrupted));
    Ok(Done { result: summary, files, failure }.strict(args.strict.strict, &validity))
}

/// A scoped thread's result, its panic carried on to the caller (as if it had
/// run on the caller's thread).
fn joined<T>(result: std::thread::Result<T>) -> T {
    result.unwrap_or_else(|panic| std::panic::resume_unwind(panic))
}

/// Runs `sil-host simulate`: [`execute`], then prints the summary (human, or the
/// JSON document with `--json`).
///
/// # Errors
/// As [`execute`]; a simulation that failed part way (after writing).
pub fn run(args: &SimulateArgs) -> Result<(), CliError> {
    crate::commands::finish(execute(args)?, args.output.json, |r| r, |r, _| print_human(r))
}
