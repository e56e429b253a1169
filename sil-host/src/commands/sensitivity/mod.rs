//! `sil-host sensitivity`: the paper's headline results under each open choice,
//! one at a time from the defaults ([`analyses::sensitivity`]). Writes
//! `sensitivity.csv` (choice, value, result), `summary.json` (the typed study) and
//! one figure per headline result.

use std::io::Write;
use std::time::Instant;

use analyses::sensitivity::{self};

use crate::commands::Done;
use crate::{
    cli::SensitivityArgs,
    error::CliError,
    output::{OutputSet, progress_bar, write_csv},
};

pub mod figures;
mod layout;
pub use experiments::sensitivity::{Summary, prepare};

/// Runs the study and writes its files; prints nothing.
///
/// # Errors
/// Bad input (exit 2) before anything is written; an interruption (exit 1, nothing
/// written); I/O and figure errors.
pub fn execute(args: &SensitivityArgs) -> Result<Done<Summary>, CliError> {
    let (base, threads) = prepare(args)?;
    crate::commands::warn(experiments::scenario::board_tables_note(&base, "the sensitivity study (the firmware in-process)"));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| CliError::bad_input(format!("cannot start {threads} worker threads: {e}")))?;
    let stop = crate::cancel::stop_flag();
    let progress = progress_bar(1, "sensitivity", "jobs", args.output.json);
    let started = Instant::now();
    let study = pool.install(|| {
        sensitivity::run(&base, args.size, args.seeds, &stop, &|done, total| {
            progress.set_length(total);
            progress.set_position(done);
        })
    })?;
    let wall_s = started.elapsed().as_secs_f64();
    progress.finish_and_clear();

    let mut out = OutputSet::new(&args.output.out)?;
    write_csv(&mut out, "sensitivity.csv", &study.rows())?;
    let mut names = vec!["sensitivity.csv".to_string(), "summary.json".to_string()];
    for fig in figures::FIGURES {
        let path = out.stage_figure(fig.file)?;
        figures::draw(&path, &study, &fig)?;
        names.push(fig.file.to_string());
        if ::figures::plot::print::WRITES_PDF {
            names.push(fig.file.replace(".svg", ".pdf"));
        }
    }
    let summary =
        Summary { study, base_scenario: base, wall_s, threads, files: names.iter().map(|f| out.path(f).display().to_string()).collect() };
    out.write_json("summary.json", &summary)?;
    let files = out.commit()?;
    let validity = summary.study.validity;
    Ok(Done::ok(summary, files).strict(args.strict.strict, &validity))
}

/// Runs `sil-host sensitivity`: [`execute`], then prints the table (or the JSON
/// document with `--json`).
///
/// # Errors
/// As [`execute`].
pub fn run(args: &SensitivityArgs) -> Result<(), CliError> {
    crate::commands::finish(execute(args)?, args.output.json, |r| r, |r, _| print_table(r))
}

/// The human table: per dimension and value, the headline results.
pub(crate) fn print_table(s: &Summary) {
    let mut o = crate::stdout::out();
    let st = &s.study;
    let _ = writeln!(
        o,
        "sensitivity study ({:?}): each open choice varied alone from the defaults; '.' = the choice does not enter that result",
        st.size
    );
    let _ = writeln!(
        o,
        "{:<24} {:<22} {:>8} {:>8} {:>17} {:>5} | Z_t,sliding (mm): pid d/u, hybrid d/u, ideal | sampled | {:>6}",
        "choice", "value", "mu* x0a", "mu* x0d", "band mu=.6 x0a", "x0d", "closed"
    );
    for r in &st.results {
        let c = &r.choice;
        let f = |x: Option<f64>| x.map_or("none".to_string(), |v| format!("{v}"));
        let (a, d, band, x0d) = match &r.open_loop {
            Some(ol) => (
                f(ol.critical_mu_x0a),
                f(ol.critical_mu_x0d),
                ol.band_text(),
                if ol.x0d_bounces { "yes".to_string() } else { "no".to_string() },
            ),
            None => (".".to_string(), ".".to_string(), ".".to_string(), ".".to_string()),
        };
        let z = |setting: analyses::zmax::Setting| {
            analyses::zmax::Combination::all()
                .into_iter()
                .filter(|k| k.setting == setting)
                .map(|k| match r.zmax.iter().find(|z| z.combination == k) {
                    Some(z) => z.cell_text(false),
                    None => ".".into(),
                })
                .collect::<Vec<String>>()
                .join("/")
        };
        let closed = r.closed_loop.as_ref().map_or(".".into(), |cl| cl.text());
        let _ = writeln!(
            o,
            "{:<24} {:<22} {:>8} {:>8} {:>17} {:>5} | {:>17} | {:>17} | {:>6}",
            c.dimension.label(),
            format!("{}{}", c.value, if c.is_default { " *" } else { "" }),
            a,
            d,
            band,
            x0d,
            z(analyses::zmax::Setting::Ideal),
            z(analyses::zmax::Setting::Sampled),
            closed
        );
    }
    let _ = writeln!(
        o,
        "* the default; mu*: critical mu; band: the longest run of neighbouring bouncing belt speeds (m/s), + the others; Z_t,sliding: largest target slid to with no lift-off (< lo: why the lowest fails); closed: how the hybrid closed loop from x0d at mu = 0.6 ended over the belt speeds"
    );
    let _ = writeln!(o, "validity (everything simulated): {}", st.validity);
    if !st.validity.is_valid() {
        let _ = writeln!(o, "INVALID: {} (left out of the results; summary.json has them per choice)", st.validity.describe_violations());
    }
    let _ = writeln!(o, "{:.1} s on {} threads; wrote {}", s.wall_s, s.threads, s.files.join(", "));
}
