//! Where and when a report was made: the date (UTC), the commit and the machine,
//! so a figure in docs/results.md says what produced it.

use serde::Serialize;

/// The stamp of a report.
#[derive(Debug, Clone, Serialize)]
pub struct Stamp {
    /// `YYYY-MM-DD HH:MM UTC`.
    pub date: String,
    /// The commit the binary was built from (`git describe --always --dirty` at
    /// build time, `sil-host/build.rs`), or `unknown` when built outside a git checkout.
    pub commit: String,
    /// Host name.
    pub host: String,
    /// CPU model (`/proc/cpuinfo`), or `unknown`.
    pub cpu: String,
    /// CPUs this process may use.
    pub cpus: usize,
    /// Kernel (`/proc/sys/kernel/osrelease`), or the OS family.
    pub os: String,
}

impl Stamp {
    /// The stamp of now, here.
    pub fn now() -> Self {
        let secs = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs());
        let read =
            |p: &str| tables::input::read_to_string(std::path::Path::new(p), tables::input::SYSTEM_FILE).ok().map(|s| s.trim().to_string());
        let cpu = read("/proc/cpuinfo")
            .and_then(|c| {
                c.lines().find(|l| l.starts_with("model name")).and_then(|l| l.split_once(':')).map(|(_, m)| m.trim().to_string())
            })
            .unwrap_or_else(|| "unknown".into());
        Self {
            date: utc(secs),
            commit: env!("SIL_HOST_COMMIT").to_string(),
            host: read("/proc/sys/kernel/hostname").unwrap_or_else(|| "unknown".into()),
            cpu,
            cpus: std::thread::available_parallelism().map_or(1, |n| n.get()),
            os: read("/proc/sys/kernel/osrelease").map_or_else(|| std::env::consts::OS.to_string(), |r| format!("Linux {r}")),
        }
    }

    /// One line: `2026-11-22 01:30 UTC, commit abc1234, host (CPU, 2 CPUs, Linux 6.1)`.
    pub fn line(&self) -> String {
        format!("{}, commit `{}`, {} ({}, {} CPUs, {})", self.date, self.commit, self.host, self.cpu, self.cpus, self.os)
    }
}

/// `secs` since the Unix epoch as `YYYY-MM-DD HH:MM UTC` (the proleptic
/// Gregorian calendar; H. Hinnant's days-to-civil algorithm).
fn utc(secs: u64) -> String {
    let days = (secs / 86_400) as i64;
    let (h, m) = ((secs % 86_400) / 3600, (secs % 3600) / 60);
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let mo = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(mo <= 2);
    format!("{y:04}-{mo:02}-{d:02} {h:02}:{m:02} UTC")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_dates() {
        assert_eq!(utc(0), "1970-01-01 00:00 UTC");
        assert_eq!(utc(951_782_400), "2000-02-29 00:00 UTC");
        assert_eq!(utc(1_795_307_400), "2026-11-22 00:30 UTC");
    }
}
