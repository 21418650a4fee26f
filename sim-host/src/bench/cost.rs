//! What a run costs the machine (issue 24's `scale` experiment): the CPU time of the thread
//! that ran it, the process's peak resident memory, and the cost table (`cost.md`).
//!
//! - CPU time: `clock_gettime(CLOCK_THREAD_CPUTIME_ID)` (POSIX) around the run loop (what the
//!   report's wall time spans), so a run on a loaded machine is charged its own CPU, not the
//!   time it waited for a core.
//! - Peak memory: Linux keeps a process's peak resident set (`VmHWM` in `/proc/self/status`)
//!   and resets it when `5` is written to `/proc/self/clear_refs` (proc(5)). It is per
//!   process: with runs overlapping (`--jobs` above 1) it is the peak of all of them; with
//!   `--jobs 1` it is the run's peak plus what the process holds anyway (the program and the
//!   records so far, a few MB; free memory the allocator kept from earlier runs is handed back
//!   first with glibc's `malloc_trim`). Elsewhere it is not reported.

use std::fmt::Write as _;

use super::record::RunRecord;

/// CPU time the calling thread has used \[s\], or `None` where the clock is missing.
pub fn thread_cpu_s() -> Option<f64> {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid, writable timespec for the duration of the call.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
    (rc == 0).then_some(t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9)
}

/// Hands the allocator's free memory back to the system (glibc's `malloc_trim`, so that what
/// earlier runs freed is not counted as resident), then resets the process's peak resident
/// memory to its current one; whether it could.
pub fn reset_peak_rss() -> bool {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only releases free memory of the allocator; no pointer is involved.
    unsafe {
        libc::malloc_trim(0);
    }
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// The process's peak resident memory since the last [`reset_peak_rss`] (or its start) \[MB\],
/// or `None` where `/proc/self/status` has no `VmHWM`.
pub fn peak_rss_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line
        .trim_start_matches("VmHWM:")
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kb / 1024.0)
}

fn cell<T>(v: Option<T>, f: impl Fn(T) -> String) -> String {
    v.map(f).unwrap_or_else(|| "—".into())
}

/// The cost table of `records`, one row per run: map, cells, robots, simulated, wall and CPU
/// seconds, real-time factors, CPU per robot per simulated second, decisions, decision time,
/// coverage and peak memory. Written as `cost.md` for the `scale` experiment.
pub fn markdown(name: &str, records: &[RunRecord]) -> String {
    let mut out = format!("# {name}: cost\n\n");
    out.push_str(
        "Simulated and wall seconds are the run loop's (`RunReport`); CPU is the thread's \
         over the same loop (not the world's generation nor the runner's set-up); real time x = simulated / \
         wall and simulated / CPU; peak RSS is the whole process's (a run's own only with \
         `--jobs 1`).\n\n",
    );
    out.push_str(
        "| map | cells | robots | simulated s | wall s | CPU s | x real time (wall) | \
         x real time (CPU) | CPU ms per robot per simulated s | decisions | decision p50 ms | \
         coverage | peak RSS MB | end |\n",
    );
    out.push_str("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n");
    for r in records {
        let s = &r.spec;
        match &r.result {
            Ok(m) => {
                let sim = m.sim_time_s;
                let per = |x: f64| (sim > 0.0 && x > 0.0).then(|| sim / x);
                let _ = writeln!(
                    out,
                    "| {} | {} | {} | {:.1} | {:.2} | {} | {} | {} | {} | {} | {} | {:.2} % | {} | {} |",
                    s.map_label,
                    cell(m.cells, |c| c.to_string()),
                    s.robots,
                    sim,
                    m.wall_time_s,
                    cell(m.cpu_time_s, |c| format!("{c:.2}")),
                    cell(per(m.wall_time_s), |x| format!("{x:.1}")),
                    cell(m.cpu_time_s.and_then(per), |x| format!("{x:.1}")),
                    cell(
                        m.cpu_time_s
                            .filter(|_| sim > 0.0)
                            .map(|c| 1e3 * c / (s.robots as f64 * sim)),
                        |x| format!("{x:.2}")
                    ),
                    m.decisions,
                    cell(m.decision_ms_quantile(0.5), |x| format!("{x:.1}")),
                    100.0 * m.coverage,
                    cell(m.peak_rss_mb, |x| format!("{x:.1}")),
                    m.reason,
                );
            }
            Err(e) => {
                let _ = writeln!(
                    out,
                    "| {} | — | {} | — | — | — | — | — | — | — | — | — | — | error: {} |",
                    s.map_label,
                    s.robots,
                    e.replace('|', "/")
                );
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::record::RunResult;
    use crate::bench::sweep::Sweep;

    #[test]
    fn the_thread_clock_counts_work_and_the_peak_follows_memory() {
        let t0 = thread_cpu_s().expect("a thread CPU clock on this platform");
        let mut x = 0u64;
        for i in 0..5_000_000u64 {
            x = x.wrapping_mul(31).wrapping_add(std::hint::black_box(i));
        }
        std::hint::black_box(x);
        let t1 = thread_cpu_s().unwrap();
        assert!(t1 > t0, "{t0} -> {t1}");
        if let Some(before) = peak_rss_mb() {
            let v = std::hint::black_box(vec![1u8; 64 << 20]);
            let after = peak_rss_mb().unwrap();
            assert!(after >= before + 32.0, "{before} MB -> {after} MB");
            drop(v);
        }
    }

    #[test]
    fn the_table_has_a_row_per_run_with_its_rates() {
        let specs = Sweep::from_json(
            r#"{"maps": ["lab"], "methods": ["xboa"], "robots": [1, 4], "runs": 1}"#,
            "t",
        )
        .unwrap()
        .specs();
        let records = vec![
            RunRecord {
                spec: specs[0].clone(),
                result: Ok(RunResult {
                    sim_time_s: 20.0,
                    wall_time_s: 0.5,
                    cpu_time_s: Some(0.4),
                    cells: Some(57_600),
                    decisions: 3,
                    ..RunResult::default()
                }),
            },
            RunRecord {
                spec: specs[1].clone(),
                result: Err("no start | for robot 3".into()),
            },
        ];
        let md = markdown("scale", &records);
        let rows: Vec<&str> = md.lines().filter(|l| l.starts_with("| lab")).collect();
        assert_eq!(rows.len(), 2, "{md}");
        // 20 s / 0.5 s wall = 40x, 20 s / 0.4 s CPU = 50x, 400 ms / (1 robot x 20 s) = 20 ms.
        assert!(rows[0].contains("| 57600 | 1 | 20.0 | 0.50 | 0.40 | 40.0 | 50.0 | 20.00 | 3 |"));
        assert!(
            rows[1].contains("error: no start / for robot 3"),
            "{}",
            rows[1]
        );
    }
}
