//! Slurm: the sbatch array script, the split of a long job list into arrays the cluster accepts,
//! and the three commands wetgran asks (`sbatch --parsable`, `scontrol show config` for
//! `MaxArraySize`, `squeue` for the state of array tasks). The text each command prints is parsed
//! by a pure function (unit-tested); the calls themselves are thin.

use std::collections::HashMap;
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// How long wetgran waits for `scontrol show config`. A Slurm client whose controller does not
/// answer retries for its `MessageTimeout` (10 s by default); the answer only sizes the arrays,
/// and [`DEFAULT_ARRAY_LIMIT`] stands in without it.
pub const SCONTROL_WAIT: Duration = Duration::from_secs(3);

/// Tasks per array where neither `--array-limit` nor the cluster's `MaxArraySize` says
/// otherwise (Slurm's own default `MaxArraySize` is 1001: task ids 0 .. 1000).
pub const DEFAULT_ARRAY_LIMIT: usize = 1000;

/// The sbatch options of a submission.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SbatchOptions {
    pub partition: Option<String>,
    /// Wall-time limit per task, in any form sbatch takes (`30`, `2:00:00`, `1-00:00:00`).
    pub time: Option<String>,
    pub cpus_per_task: u32,
}

/// One array to submit.
#[derive(Debug, Clone, PartialEq)]
pub struct ArrayScript<'a> {
    /// The sweep's name (job name `wetgran-<name>`).
    pub sweep: &'a str,
    /// The sweep directory (absolute).
    pub dir: &'a Path,
    /// The task list file: line k + 1 is the job id of task k.
    pub tasks_file: &'a Path,
    /// Number of tasks.
    pub tasks: usize,
    /// The wetgran executable the tasks run (absolute, on the shared filesystem).
    pub wetgran: &'a Path,
    pub options: &'a SbatchOptions,
}

/// `'text'` for the shell: single quotes, an inner `'` as `'\''`.
pub fn shell_quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// Checks a value that goes on an `#SBATCH` line (where no quoting is possible): no whitespace,
/// no control character, not empty.
pub fn check_directive(what: &str, value: &str) -> Result<(), String> {
    if value.is_empty() || value.chars().any(|c| c.is_whitespace() || c.is_control()) {
        return Err(format!(
            "{what} `{value}` cannot go on an #SBATCH line: it must be non-empty and have no \
             spaces or control characters"
        ));
    }
    Ok(())
}

/// A sweep name as a file or job name: anything but ASCII letters, digits, `-`, `_` and `.`
/// replaced by `_` (and a leading `.` too).
pub fn file_name(sweep: &str) -> String {
    sweep
        .chars()
        .enumerate()
        .map(|(k, c)| {
            if c.is_ascii_alphanumeric() || "-_".contains(c) || (c == '.' && k > 0) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The sbatch script of one array. Task `SLURM_ARRAY_TASK_ID` = k runs the job on line k + 1 of
/// the task list: `wetgran job run DIR/specs/<id>.json --out DIR/results/<id>.json`.
pub fn array_script(a: &ArrayScript) -> Result<String, String> {
    if a.tasks == 0 {
        return Err("an array needs at least one task".to_string());
    }
    let dir = a.dir.display().to_string();
    check_directive("the sweep directory", &dir)?;
    let mut optional = String::new();
    for (flag, value) in [
        ("--partition", &a.options.partition),
        ("--time", &a.options.time),
    ] {
        if let Some(v) = value {
            check_directive(flag, v)?;
            optional += &format!("#SBATCH {flag}={v}\n");
        }
    }
    Ok(format!(
        "#!/bin/bash\n\
         # wetgran sweep {sweep}: {tasks} job(s) as one Slurm array, written by `wetgran sweep \
         submit`.\n\
         # Task k runs the job on line k + 1 of the task list; it reads only its spec and writes \
         only its result file.\n\
         #SBATCH --job-name=wetgran-{name}\n\
         #SBATCH --array=0-{last}\n\
         #SBATCH --ntasks=1\n\
         #SBATCH --cpus-per-task={cpus}\n\
         {optional}\
         #SBATCH --output={dir}/logs/%A_%a.out\n\
         set -eu\n\
         dir={quoted_dir}\n\
         id=$(sed -n \"$((SLURM_ARRAY_TASK_ID + 1))p\" {tasks_file})\n\
         if [ -z \"$id\" ]; then\n    echo \"wetgran: no job for array task \
         $SLURM_ARRAY_TASK_ID in the task list\" >&2\n    exit 2\nfi\n\
         exec {wetgran} job run \"$dir/specs/$id.json\" --out \"$dir/results/$id.json\"\n",
        sweep = a.sweep,
        tasks = a.tasks,
        name = file_name(a.sweep),
        last = a.tasks - 1,
        cpus = a.options.cpus_per_task.max(1),
        quoted_dir = shell_quote(&dir),
        tasks_file = shell_quote(&a.tasks_file.display().to_string()),
        wetgran = shell_quote(&a.wetgran.display().to_string()),
    ))
}

/// The tasks per array: the smaller of `--array-limit` (default [`DEFAULT_ARRAY_LIMIT`]) and
/// the cluster's `MaxArraySize` (task ids run from 0 to `MaxArraySize - 1`).
pub fn array_limit(flag: Option<usize>, max_array_size: Option<usize>) -> usize {
    let want = flag.unwrap_or(DEFAULT_ARRAY_LIMIT).max(1);
    match max_array_size {
        Some(m) if m >= 1 => want.min(m),
        _ => want,
    }
}

/// Splits `jobs` into consecutive arrays of at most `limit` tasks.
pub fn split<T>(jobs: &[T], limit: usize) -> Vec<&[T]> {
    jobs.chunks(limit.max(1)).collect()
}

/// `MaxArraySize` from the text of `scontrol show config`.
pub fn parse_max_array_size(config: &str) -> Option<usize> {
    config.lines().find_map(|l| {
        let (k, v) = l.split_once('=')?;
        (k.trim() == "MaxArraySize")
            .then(|| v.trim().parse().ok())
            .flatten()
    })
}

/// The job id from `sbatch --parsable` (`ID` or `ID;CLUSTER`).
pub fn parse_sbatch(stdout: &str) -> Option<String> {
    let line = stdout.lines().map(str::trim).find(|l| !l.is_empty())?;
    let id = line.split(';').next()?.trim();
    (!id.is_empty() && id.chars().all(|c| c.is_ascii_digit())).then(|| id.to_string())
}

/// Job states in which a task has ended: some Slurm versions list them for a while when asked
/// for a job by id; such a task counts as gone from the queue.
pub const ENDED_STATES: [&str; 11] = [
    "COMPLETED",
    "FAILED",
    "TIMEOUT",
    "CANCELLED",
    "NODE_FAIL",
    "OUT_OF_MEMORY",
    "BOOT_FAIL",
    "DEADLINE",
    "PREEMPTED",
    "SPECIAL_EXIT",
    "REVOKED",
];

/// The state of each queued array task from `squeue -h -r -o '%i %T' -j ID` (lines `ID_TASK
/// STATE`); lines of other jobs and tasks in one of the [`ENDED_STATES`] are left out.
pub fn parse_squeue(stdout: &str, array_job: &str) -> HashMap<i64, String> {
    let mut out = HashMap::new();
    for line in stdout.lines() {
        let mut parts = line.split_whitespace();
        let (Some(id), Some(state)) = (parts.next(), parts.next()) else {
            continue;
        };
        if let Some((job, task)) = id.split_once('_')
            && job == array_job
            && let Ok(task) = task.parse::<i64>()
            && !ENDED_STATES.contains(&state)
        {
            out.insert(task, state.to_string());
        }
    }
    out
}

/// Runs `cmd` and returns its output, or `None` where it cannot start or has not finished within
/// `limit` (it is then killed). Its standard output and error are read on their own threads,
/// so a long answer cannot block it on a full pipe.
pub fn output_within(cmd: &mut Command, limit: Duration) -> Option<Output> {
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .ok()?;
    let read = |pipe: Option<Box<dyn std::io::Read + Send>>| {
        std::thread::spawn(move || {
            let mut buf = Vec::new();
            if let Some(mut p) = pipe {
                let _ = p.read_to_end(&mut buf);
            }
            buf
        })
    };
    let out = read(child.stdout.take().map(|p| Box::new(p) as _));
    let err = read(child.stderr.take().map(|p| Box::new(p) as _));
    let start = Instant::now();
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) if start.elapsed() < limit => {
                std::thread::sleep(Duration::from_millis(20));
            }
            _ => {
                let _ = child.kill();
                let _ = child.wait();
                return None;
            }
        }
    };
    Some(Output {
        status,
        stdout: out.join().unwrap_or_default(),
        stderr: err.join().unwrap_or_default(),
    })
}

/// The cluster's `MaxArraySize`, where `scontrol` answers within [`SCONTROL_WAIT`].
pub fn max_array_size() -> Option<usize> {
    let out = output_within(
        Command::new("scontrol").args(["show", "config"]),
        SCONTROL_WAIT,
    )?;
    out.status
        .success()
        .then(|| parse_max_array_size(&String::from_utf8_lossy(&out.stdout)))
        .flatten()
}

/// Submits a script; returns the job id.
pub fn sbatch(script: &Path) -> Result<String, String> {
    let out = Command::new("sbatch")
        .arg("--parsable")
        .arg(script)
        .output()
        .map_err(|e| format!("cannot run sbatch: {e} (is Slurm installed on this machine?)"))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        return Err(format!(
            "sbatch {} failed: {}",
            script.display(),
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    parse_sbatch(&stdout).ok_or_else(|| format!("sbatch answered no job id: {stdout:?}"))
}

/// Where a query of the Slurm queue stands.
#[derive(Debug, Clone, PartialEq)]
pub enum Queue {
    /// `squeue` is not available (not installed, or no controller answers).
    Unavailable(String),
    /// The state of each queued array task of the job (`PENDING`, `RUNNING`, ...); a task that
    /// is not listed has left the queue.
    Tasks(HashMap<i64, String>),
}

/// The queued tasks of an array job.
pub fn squeue(array_job: &str) -> Queue {
    let out = match Command::new("squeue")
        .args(["-h", "-r", "-o", "%i %T", "-j", array_job])
        .output()
    {
        Ok(o) => o,
        Err(e) => return Queue::Unavailable(format!("cannot run squeue: {e}")),
    };
    let stderr = String::from_utf8_lossy(&out.stderr);
    if out.status.success() {
        Queue::Tasks(parse_squeue(
            &String::from_utf8_lossy(&out.stdout),
            array_job,
        ))
    } else if stderr.contains("Invalid job id") {
        // Slurm forgets a finished job after MinJobAge: nothing of it is queued.
        Queue::Tasks(HashMap::new())
    } else {
        Queue::Unavailable(format!("squeue failed: {}", stderr.trim()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn script(tasks: usize, options: &SbatchOptions) -> Result<String, String> {
        array_script(&ArrayScript {
            sweep: "my sweep",
            dir: Path::new("/shared/w/wetgran-slurm/my_sweep"),
            tasks_file: &PathBuf::from("/shared/w/wetgran-slurm/my_sweep/arrays/array-3.tasks"),
            tasks,
            wetgran: Path::new("/opt/it's/wetgran"),
            options,
        })
    }

    #[test]
    fn the_array_script_has_the_directives_and_runs_one_job_per_task() {
        let opts = SbatchOptions {
            partition: Some("short".to_string()),
            time: Some("2:00:00".to_string()),
            cpus_per_task: 2,
        };
        let s = script(250, &opts).unwrap();
        let lines: Vec<&str> = s.lines().collect();
        assert_eq!(lines[0], "#!/bin/bash");
        for want in [
            "#SBATCH --job-name=wetgran-my_sweep",
            "#SBATCH --array=0-249",
            "#SBATCH --cpus-per-task=2",
            "#SBATCH --partition=short",
            "#SBATCH --time=2:00:00",
            "#SBATCH --output=/shared/w/wetgran-slurm/my_sweep/logs/%A_%a.out",
        ] {
            assert!(lines.contains(&want), "missing {want:?} in\n{s}");
        }
        // sbatch stops reading directives at the first command: all come before `set`.
        let first_cmd = lines.iter().position(|l| *l == "set -eu").unwrap();
        assert!(
            lines
                .iter()
                .enumerate()
                .all(|(k, l)| !l.starts_with("#SBATCH") || k < first_cmd)
        );
        // The executable path is quoted for the shell (an inner quote survives).
        assert!(s.contains(r"exec '/opt/it'\''s/wetgran' job run"), "{s}");
        assert!(s.contains("--out \"$dir/results/$id.json\""), "{s}");
        // Without options: no partition, no time line (the cluster's defaults), one CPU.
        let s = script(1, &SbatchOptions::default()).unwrap();
        assert!(s.contains("#SBATCH --array=0-0\n"));
        assert!(s.contains("#SBATCH --cpus-per-task=1\n"));
        assert!(!s.contains("--partition") && !s.contains("--time"));
    }

    #[test]
    fn the_array_script_runs_the_task_of_its_line_under_bash() {
        // Run the script's body with a stub wetgran that prints its arguments.
        let dir = tempfile::tempdir().unwrap();
        let tasks = dir.path().join("t.tasks");
        std::fs::write(&tasks, "aaa\nbbb\nccc\n").unwrap();
        let stub = dir.path().join("stub");
        std::fs::write(&stub, "#!/bin/sh\necho \"$@\"\n").unwrap();
        std::process::Command::new("chmod")
            .args(["+x", stub.to_str().unwrap()])
            .status()
            .unwrap();
        let opts = SbatchOptions::default();
        let s = array_script(&ArrayScript {
            sweep: "s",
            dir: dir.path(),
            tasks_file: &tasks,
            tasks: 3,
            wetgran: &stub,
            options: &opts,
        })
        .unwrap();
        let run = |task: &str| {
            std::process::Command::new("bash")
                .arg("-c")
                .arg(&s)
                .env("SLURM_ARRAY_TASK_ID", task)
                .output()
                .unwrap()
        };
        let out = run("1");
        assert!(out.status.success());
        let d = dir.path().display();
        assert_eq!(
            String::from_utf8_lossy(&out.stdout).trim(),
            format!("job run {d}/specs/bbb.json --out {d}/results/bbb.json")
        );
        // A task id past the list fails with a message instead of running nothing quietly.
        let out = run("3");
        assert_eq!(out.status.code(), Some(2));
        assert!(String::from_utf8_lossy(&out.stderr).contains("no job for array task 3"));
    }

    #[test]
    fn values_that_cannot_go_on_an_sbatch_line_are_refused() {
        let opts = SbatchOptions {
            partition: Some("a b".to_string()),
            ..Default::default()
        };
        let e = script(2, &opts).unwrap_err();
        assert!(e.contains("--partition `a b`"), "{e}");
        let opts = SbatchOptions {
            time: Some("1:00\n#SBATCH --mem=1T".to_string()),
            ..Default::default()
        };
        assert!(script(2, &opts).is_err());
        assert!(script(0, &SbatchOptions::default()).is_err());
    }

    #[test]
    fn jobs_are_split_at_the_smaller_of_the_flag_and_max_array_size() {
        assert_eq!(array_limit(None, None), DEFAULT_ARRAY_LIMIT);
        assert_eq!(array_limit(Some(300), None), 300);
        assert_eq!(array_limit(None, Some(1001)), 1000);
        assert_eq!(array_limit(Some(5000), Some(1001)), 1001);
        assert_eq!(array_limit(Some(10), Some(1001)), 10);
        assert_eq!(array_limit(Some(0), None), 1);
        let jobs: Vec<u32> = (0..2501).collect();
        let parts = split(&jobs, array_limit(None, Some(1001)));
        assert_eq!(
            parts.iter().map(|p| p.len()).collect::<Vec<_>>(),
            [1000, 1000, 501]
        );
        // Every job once, in order.
        assert_eq!(parts.concat(), jobs);
    }

    #[test]
    fn command_outputs_parse() {
        let config = "Configuration data as of 2026-11-22T15:00:00\nMailProg                = \
                      /bin/mail\nMaxArraySize            = 1001\nMaxJobCount             = 10000\n";
        assert_eq!(parse_max_array_size(config), Some(1001));
        assert_eq!(parse_max_array_size("MaxJobCount = 5\n"), None);
        assert_eq!(parse_sbatch("4242\n"), Some("4242".to_string()));
        assert_eq!(parse_sbatch("4242;cluster1\n"), Some("4242".to_string()));
        assert_eq!(parse_sbatch("Submitted batch job 4242\n"), None);
        assert_eq!(file_name("../a b/c.d"), "_._a_b_c.d");
        let q = parse_squeue(
            "17_0 RUNNING\n17_3 PENDING\n18_0 RUNNING\nbad\n17_4 TIMEOUT\n17_5 COMPLETED\n",
            "17",
        );
        assert_eq!(q.len(), 2);
        assert_eq!(q[&0], "RUNNING");
        assert_eq!(q[&3], "PENDING");
    }

    #[test]
    fn a_command_that_does_not_answer_in_time_is_killed() {
        // `sleep 600` stands for a Slurm client waiting on a controller that is not up; the
        // test finishing at all shows it was killed.
        let mut sleep = Command::new("sleep");
        sleep.arg("600");
        assert!(output_within(&mut sleep, Duration::from_millis(200)).is_none());
        let mut echo = Command::new("echo");
        echo.arg("MaxArraySize           = 40001");
        let out = output_within(&mut echo, Duration::from_secs(60)).expect("echo answers");
        assert!(out.status.success());
        assert_eq!(
            parse_max_array_size(&String::from_utf8_lossy(&out.stdout)),
            Some(40001)
        );
        // A command that cannot start gives no answer either.
        assert!(output_within(&mut Command::new("/nonexistent/scontrol"), SCONTROL_WAIT).is_none());
    }
}
