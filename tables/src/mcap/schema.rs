//! The JSON Schemas of an MCAP file's channels (schema encoding `jsonschema`):
//! each group's fields, their types and, in the descriptions, their units; and
//! the kind names of the tables' metadata records.

use super::McapGroup;
use crate::Kind;

/// What a column holds and in which unit, for the JSON Schema's descriptions
/// (the CLI's tables' columns; another gets its name).
pub(super) fn describe(name: &str) -> &str {
    match name {
        "t" => "time, s (log time: t in ns)",
        "theta1" => "shoulder angle theta1, rad",
        "theta1_dot" => "shoulder rate theta1_dot, rad/s",
        "theta2" => "elbow angle theta2, rad",
        "theta2_dot" => "elbow rate theta2_dot, rad/s",
        "energy" => "mechanical energy (kinetic + gravity + spring), J",
        "mode" => "contact mode: flight, sliding or sticking",
        "f_t" => "tangential contact force f_t, N",
        "f_n" => "normal contact force f_n, N",
        "z_t" => "tip tangential position z_t, m",
        "z_n" => "tip normal position z_n (height above the belt), m",
        "z_t_dot" => "tip tangential velocity z_t_dot, m/s",
        "z_n_dot" => "tip normal velocity z_n_dot, m/s",
        "z_r_dot" => "relative tangential velocity z_t_dot - v_belt, m/s",
        "z_t_ref" => "the firmware's reference z_t*, m",
        "lift_off_true" => "the tip in flight at t (true lift-off)",
        "u1_cmd" => "shoulder torque u1 taking effect in this period, N m",
        "u2_cmd" => "elbow torque u2 taking effect in this period, N m",
        "u1_applied" => "shoulder torque u1 applied at t (the previous command), N m",
        "u2_applied" => "elbow torque u2 applied at t (the previous command), N m",
        "lift_off_detected" => "lift-off as the firmware reports it",
        "deadline_miss" => "deadline miss seen by the plant (the previous command held)",
        "firmware_deadline_miss" => "deadline miss counted by the firmware (DEADLINE_MISS)",
        "overruns" => "the firmware's overrun counter (0 without a command)",
        "status" => "the firmware's status word (0 without a command)",
        "kind" => "the event: touchdown, lift_off, p_zero, jam, slip_to_stick, ...",
        "mode_after" => "contact mode after the event",
        "v_n_before" => "normal tip velocity before the event, m/s",
        "v_n_after" => "normal tip velocity after the event, m/s",
        "v_r_before" => "relative tangential velocity before the event, m/s",
        "v_r_after" => "relative tangential velocity after the event, m/s",
        "impulse_t" => "tangential impulse of an impact, N s",
        "impulse_n" => "normal impulse of an impact, N s",
        "energy_change" => "change of mechanical energy at the event, J",
        "contact_work" => "work of the contact impulse, J",
        "resolution" => "how an impact was resolved (empty when not an impact)",
        other => other,
    }
}

/// The name of a column kind in the metadata record (`f64`, `str`, `bool`, `int`).
pub(super) fn kind_name(k: Kind) -> &'static str {
    match k {
        Kind::F64 => "f64",
        Kind::Str => "str",
        Kind::Bool => "bool",
        Kind::Int => "int",
    }
}

/// The JSON Schema (draft 2020-12) of a group's messages: an object with `t`
/// and the group's columns, in the messages' order, all required; floats are
/// `number` or `null` (NaN).
pub(super) fn schema_json(names: &[&str], kinds: &[Kind], group: &McapGroup) -> Result<Vec<u8>, String> {
    // Built as text: serde_json's maps sort their keys, and the order of the
    // properties is what Foxglove lists.
    let quote = |s: &str| serde_json::to_string(s).unwrap_or_default();
    let mut properties = Vec::new();
    let mut required = Vec::new();
    for name in std::iter::once(&"t").chain(group.columns) {
        let i = names.iter().position(|n| n == name).ok_or_else(|| format!("group {}: no column `{name}`", group.topic))?;
        let t = match kinds[i] {
            Kind::F64 => r#"["number","null"]"#,
            Kind::Str => r#""string""#,
            Kind::Bool => r#""boolean""#,
            Kind::Int => r#""integer""#,
        };
        properties.push(format!(r#"{}:{{"type":{t},"description":{}}}"#, quote(name), quote(describe(name))));
        required.push(quote(name));
    }
    let schema = format!(
        r#"{{"$schema":"https://json-schema.org/draft/2020-12/schema","title":{},"type":"object","properties":{{{}}},"required":[{}]}}"#,
        quote(group.schema),
        properties.join(","),
        required.join(",")
    );
    // Checked to parse, so a bad name or description fails here and not in a reader.
    serde_json::from_str::<serde_json::Value>(&schema).map_err(|e| format!("group {}: schema: {e}", group.topic))?;
    Ok(schema.into_bytes())
}
