//! The property of the target: an accepted scenario within every documented
//! bound, its firmware configuration accepted, its round trip exact; an error
//! naming its place; `from_toml_with` agreeing with `from_toml` and
//! `with_overrides`.

use firmware::Firmware;
use rig::{
    faults::FaultKind,
    overrides::Override,
    scenario::{Scenario, ScenarioError},
    setup::firmware_config,
};
use toml::Value;

use super::{case::Case, document::text, keys::KEYS};
use crate::ensure;

/// Every documented bound (docs/rig.md, "The scenario file") that `s` breaks,
/// checked here without `Scenario::validate`.
pub fn violations(s: &Scenario) -> Vec<String> {
    let mut v = Vec::new();
    let mut need = |ok: bool, what: &str| {
        if !ok {
            v.push(what.to_string());
        }
    };
    let fin = |x: f64| x.is_finite();
    let within = |x: f64, lo: f64, hi: f64| x.is_finite() && lo <= x && x <= hi;
    let name_chars = s.name.chars().count();
    need((1..=64).contains(&name_chars), "name: 1 to 64 characters");
    need(s.faults.len() <= 1000, "faults: at most 1000");
    let p = &s.plant;
    need(within(p.mu, 0.0, 10.0), "plant.mu in [0, 10]");
    need(within(p.v_belt, -5.0, 5.0), "plant.v_belt within +-5");
    need(within(p.e_n, 0.0, 1.0), "plant.e_n in [0, 1]");
    need(within(p.rtol, 1e-14, 0.1), "plant.rtol in [1e-14, 0.1]");
    need(within(p.atol, 1e-14, 0.1), "plant.atol in [1e-14, 0.1]");
    let arm = |need: &mut dyn FnMut(bool, &str), prefix: &str, m: f64, l: f64, sigma: f64, k: f64, h: f64, alpha0: f64, g: f64| {
        for (name, x) in [("m", m), ("l", l), ("h", h), ("g", g)] {
            need(fin(x) && x > 0.0, &format!("{prefix}.{name} finite and > 0"));
        }
        for (name, x) in [("sigma", sigma), ("k", k)] {
            need(fin(x) && x >= 0.0, &format!("{prefix}.{name} finite and >= 0"));
        }
        need(fin(alpha0), &format!("{prefix}.alpha0 finite"));
        need(h < 2.0 * l, &format!("{prefix}.h < 2 l"));
    };
    arm(&mut need, "plant", p.m, p.l, p.sigma, p.k, p.h, p.alpha0, p.g);
    let c = &s.controller;
    need(fin(c.target_z_t) && c.target_z_t.abs() < 2.0 * p.l, "controller.target_z_t: |z_t*| < 2 l");
    need(fin(c.move_time_s) && c.move_time_s > 0.0 && c.move_time_s <= 1e5, "controller.move_time_s in (0, 1e5]");
    need(within(c.f_n_ref, 0.0, 20.0), "controller.f_n_ref in [0, 20]");
    need(within(c.mu_hat, 0.0, 10.0), "controller.mu_hat in [0, 10]");
    // The firmware's f32 (docs/rig.md): at most 3.4e38, positive values not rounding to 0.
    let f32_fin = |x: f64| (x as f32).is_finite();
    let gain = |x: f64| fin(x) && x >= 0.0 && f32_fin(x);
    for (name, g) in [("kp", c.pid.kp), ("ki", c.pid.ki), ("kd", c.pid.kd)] {
        need(g.iter().all(|&x| gain(x)), &format!("controller.pid.{name}: finite gains >= 0"));
    }
    need(gain(c.hybrid.kp) && gain(c.hybrid.kd), "controller.hybrid.kp, kd: finite >= 0");
    need(c.hybrid.ki.is_none_or(gain), "controller.hybrid.ki: finite >= 0");
    if let Some(m) = &c.model {
        let g = |x: Option<f64>, plant: f64| x.unwrap_or(plant);
        let l = g(m.l, p.l);
        arm(
            &mut need,
            "controller.model",
            g(m.m, p.m),
            l,
            g(m.sigma, p.sigma),
            g(m.k, p.k),
            g(m.h, p.h),
            g(m.alpha0, p.alpha0),
            g(m.g, p.g),
        );
        need(c.target_z_t.abs() < 2.0 * l, "controller.target_z_t: |z_t*| < 2 controller.model.l");
    }
    let model = c.model.unwrap_or_default();
    let fw = |x: Option<f64>, plant: f64| x.unwrap_or(plant) as f32;
    let (m, l, h, g) = (fw(model.m, p.m), fw(model.l, p.l), fw(model.h, p.h), fw(model.g, p.g));
    let (sigma, k, alpha0) = (fw(model.sigma, p.sigma), fw(model.k, p.k), fw(model.alpha0, p.alpha0));
    need([m, l, h, g, sigma, k, alpha0].iter().all(|x| x.is_finite()), "the firmware's model finite in f32");
    need(m > 0.0 && l > 0.0 && h > 0.0 && g > 0.0, "the firmware's m, l, h, g > 0 in f32");
    need(h < 2.0 * l, "the firmware's h < 2 l in f32");
    need((c.target_z_t as f32).abs() < 2.0 * l, "controller.target_z_t: |z_t*| < 2 l in f32");
    need((c.move_time_s as f32) > 0.0, "controller.move_time_s > 0 in f32");
    let t = &s.timing;
    need(within(t.rate_hz, 250.0, 10_000.0), "timing.rate_hz in [250, 10000]");
    // One period: the rate's, rounded to whole microseconds (shared::time).
    let period_s = (1e6 / t.rate_hz).round() / 1e6;
    need(fin(t.delta_s) && t.delta_s >= 0.0 && t.delta_s < period_s, "timing.delta_s in [0, one period)");
    need(!s.controller.runaway_limits || t.delta_s <= 0.4e-3, "timing.delta_s at most 0.4 ms with the protection on");
    need(fin(t.duration_s) && t.duration_s > 0.0 && t.duration_s <= 1e5, "timing.duration_s in (0, 1e5]");
    need(within(s.sensors.load_noise_n, 0.0, 25.0), "sensors.load_noise_n in [0, 25]");
    need((10..=16).contains(&s.sensors.encoder_bits), "sensors.encoder_bits 10 to 16");
    let r = &s.rig;
    need(fin(r.command_timeout_s) && r.command_timeout_s > 0.0 && r.command_timeout_s <= 60.0, "rig.command_timeout_s in (0, 60]");
    need(within(r.spin_us, 0.0, 1e6), "rig.spin_us in [0, 1e6]");
    need(fin(r.peer_check_s) && r.peer_check_s > 0.0 && r.peer_check_s <= 60.0, "rig.peer_check_s in (0, 60]");
    need(r.max_consecutive_timeouts >= 1, "rig.max_consecutive_timeouts >= 1");
    let cpu = r.realtime_cpu.trim();
    let digits = cpu.strip_prefix('+').unwrap_or(cpu);
    let number = !digits.is_empty()
        && digits.bytes().all(|b| b.is_ascii_digit())
        && digits.trim_start_matches('0').len() <= 4
        && digits.parse::<u32>().is_ok_and(|n| n < 1024);
    need(cpu == "last" || cpu == "none" || number, "rig.realtime_cpu: last, none or a CPU number below 1024");
    need(r.realtime_fifo_priority <= 99, "rig.realtime_fifo_priority 0 to 99");
    need(fin(r.connect_timeout_s) && r.connect_timeout_s > 0.0 && r.connect_timeout_s <= 600.0, "rig.connect_timeout_s in (0, 600]");
    for (i, f) in s.faults.iter().enumerate() {
        need(fin(f.at_s) && f.at_s >= 0.0 && f.at_s < t.duration_s, &format!("faults[{i}].at_s in [0, timing.duration_s)"));
        need(within(f.duration_s, 0.0, 1e5), &format!("faults[{i}].duration_s in [0, 1e5]"));
        let sensor = matches!(f.kind, FaultKind::StuckSensor | FaultKind::NanSensor | FaultKind::OutOfRange);
        need(!sensor || f.signal.is_some(), &format!("faults[{i}]: a sensor fault has a signal"));
        need(fin(f.delay_s) && f.delay_s >= 0.0 && f.delay_s < 10.0, &format!("faults[{i}].delay_s in [0, 10)"));
        need(f.kind != FaultKind::LateCommand || f.delay_s > 0.0, &format!("faults[{i}].delay_s of a late_command in (0, 10)"));
        need(
            f.kind != FaultKind::Stall || (f.duration_s > 0.0 && f.duration_s <= 60.0),
            &format!("faults[{i}].duration_s of a stall in (0, 60]"),
        );
    }
    v
}

/// Whether an error message names its place: not empty, and a key in backticks
/// (`scenario key \`plant.m\``, ``unknown field `muu` ``), a `--set` argument, a
/// line and column of the TOML text, or, for the one TOML error without a place
/// (the reader's nesting limit), that the scenario is not valid TOML and why.
pub fn error_names_its_place(msg: &str) -> bool {
    let backticked = msg.split('`').count() >= 3;
    let located = msg.contains("at line ") && msg.contains(", column ");
    let said = msg.strip_prefix("the scenario is not valid TOML: ").is_some_and(|why| !why.trim().is_empty());
    !msg.trim().is_empty() && (backticked || located || said || msg.contains("--set "))
}

/// The paths of the non-finite floats in `v`.
fn non_finite(v: &Value, at: &str, out: &mut Vec<String>) {
    match v {
        Value::Float(x) if !x.is_finite() => out.push(at.to_string()),
        Value::Array(a) => a.iter().enumerate().for_each(|(i, x)| non_finite(x, &format!("{at}[{i}]"), out)),
        Value::Table(t) => t.iter().for_each(|(k, x)| non_finite(x, &format!("{at}.{k}"), out)),
        _ => {}
    }
}

/// Checks an accepted scenario: bounds, firmware configuration, round trip.
///
/// # Errors
/// What is wrong.
pub fn check_accepted(s: &Scenario) -> Result<(), String> {
    let v = violations(s);
    ensure(v.is_empty(), || format!("accepted a scenario that breaks documented bounds: {v:?}"))?;
    // Every number, used or not (a NaN in an unused field reads back as `null` from summary.json).
    let table = toml::Table::try_from(s).map_err(|e| format!("an accepted scenario is not a TOML table: {e}"))?;
    let mut odd = Vec::new();
    non_finite(&Value::Table(table), "", &mut odd);
    ensure(odd.is_empty(), || format!("accepted a scenario with non-finite numbers at {odd:?}"))?;
    Firmware::new(firmware_config(s)).map_err(|e| format!("accepted a scenario whose firmware configuration the firmware refuses: {e}"))?;
    let written = toml::to_string(s).map_err(|e| format!("an accepted scenario cannot be written as TOML: {e}"))?;
    match Scenario::from_toml(&written) {
        Ok(back) => ensure(format!("{back:?}") == format!("{s:?}"), || {
            format!("round trip changed the scenario:\n{written}\nread back as {back:?}")
        }),
        Err(e) => Err(format!("an accepted scenario, written as TOML, is refused: {e}\n{written}")),
    }
}

fn check_refused(e: &ScenarioError) -> Result<(), String> {
    let msg = e.to_string();
    ensure(error_names_its_place(&msg), || format!("the error names no key nor place: {msg:?}"))?;
    if let ScenarioError::OutOfRange { key, .. } = e {
        let known = KEYS.contains(&key.as_str()) || key == "faults" || key == "controller.hybrid.ki";
        ensure(known, || format!("out-of-range error names `{key}`, not a scenario key"))?;
    }
    Ok(())
}

/// The property of this target (the `scenario` module's docs).
///
/// # Errors
/// What is wrong.
pub fn check(case: &Case) -> Result<(), String> {
    let text = text(&case.source);
    let mut overrides = Vec::new();
    for arg in &case.sets {
        match arg.text().parse::<Override>() {
            Ok(o) => overrides.push(o),
            Err(e) => {
                let msg = e.to_string();
                ensure(error_names_its_place(&msg) && msg.contains("--set"), || format!("--set error names no argument: {msg:?}"))?;
            }
        }
    }
    let plain = Scenario::from_toml(&text);
    let with = Scenario::from_toml_with(&text, &overrides);
    for r in [&plain, &with] {
        match r {
            Ok(s) => check_accepted(s)?,
            Err(e) => check_refused(e)?,
        }
    }
    if overrides.is_empty() {
        let same = match (&plain, &with) {
            (Ok(a), Ok(b)) => a == b,
            (Err(a), Err(b)) => a.to_string() == b.to_string(),
            _ => false,
        };
        ensure(same, || format!("from_toml gives {plain:?}, from_toml_with without overrides {with:?}"))?;
    } else if let (Ok(base), Ok(s)) = (&plain, &with) {
        match base.with_overrides(&overrides) {
            Ok(again) => ensure(&again == s, || format!("with_overrides gives {again:?}, from_toml_with {s:?}"))?,
            Err(e) => return Err(format!("from_toml_with accepts, from_toml + with_overrides refuses: {e}")),
        }
    }
    Ok(())
}
