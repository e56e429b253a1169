//! The protobuf schemas of an MCAP file's table channels (schema encoding
//! `protobuf`: a `FileDescriptorSet`, as the MCAP spec's well-known encodings
//! define it): each group's message, its fields' types and numbers and, in the
//! fields' comments, their units.

use prost::Message as _;
use prost_types::{
    DescriptorProto, FieldDescriptorProto, FileDescriptorProto, FileDescriptorSet, SourceCodeInfo,
    field_descriptor_proto::{Label, Type},
    source_code_info::Location,
};

use super::McapGroup;
use crate::declared::Kind;

/// What a column holds and in which unit, for the fields' comments
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

/// The protobuf type of a column of kind `kind`: `double` (NaN and infinities
/// kept with their bits), `int64`, `bool`, `string`.
pub(super) fn proto_type(kind: Kind) -> Type {
    match kind {
        Kind::F64 => Type::Double,
        Kind::Int => Type::Int64,
        Kind::Bool => Type::Bool,
        Kind::Str => Type::String,
    }
}

/// The `FileDescriptorSet` (protobuf-encoded) of a group's messages: one
/// proto3 file `<package>/<Name>.proto` holding the message `group.schema`
/// (`painleve.State`: package `painleve`, message `State`), its fields `t`
/// (number 1) and then the group's columns (numbers 2, 3, ... in order), each
/// of its column's [`proto_type`], with the column's meaning and unit
/// ([`describe`]) as the field's leading comment.
///
/// # Errors
/// A message when the group names a column that `names` lacks, or its schema
/// name is not `<package>.<Message>`.
pub(super) fn schema_proto(names: &[&str], kinds: &[Kind], group: &McapGroup) -> Result<Vec<u8>, String> {
    let (package, message) = group
        .schema
        .rsplit_once('.')
        .filter(|(p, m)| !p.is_empty() && !m.is_empty())
        .ok_or_else(|| format!("group {}: schema `{}` is not <package>.<Message>", group.topic, group.schema))?;
    let mut fields = Vec::new();
    let mut comments = Vec::new();
    for (number, name) in (1..).zip(std::iter::once(&"t").chain(group.columns)) {
        let i = names.iter().position(|n| n == name).ok_or_else(|| format!("group {}: no column `{name}`", group.topic))?;
        fields.push(FieldDescriptorProto {
            name: Some(name.to_string()),
            number: Some(number),
            label: Some(Label::Optional as i32),
            r#type: Some(proto_type(kinds[i]) as i32),
            json_name: Some(name.to_string()),
            ..Default::default()
        });
        // Path: FileDescriptorProto.message_type (4) [0], DescriptorProto.field (2) [k].
        comments.push(Location {
            path: vec![4, 0, 2, number - 1],
            span: vec![0, 0, 0],
            leading_comments: Some(format!(" {}\n", describe(name))),
            ..Default::default()
        });
    }
    let file = FileDescriptorProto {
        name: Some(format!("{}/{message}.proto", package.replace('.', "/"))),
        package: Some(package.to_string()),
        message_type: vec![DescriptorProto { name: Some(message.to_string()), field: fields, ..Default::default() }],
        source_code_info: Some(SourceCodeInfo { location: comments }),
        syntax: Some("proto3".into()),
        ..Default::default()
    };
    Ok(FileDescriptorSet { file: vec![file] }.encode_to_vec())
}
