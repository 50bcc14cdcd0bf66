-- Cluster submissions (`wetgran sweep submit --slurm`): one row per submitted job array, one
-- row per array task naming the job it runs and what `sweep collect` found for it. The jobs table
-- is not touched at submission: a job stays pending until its result is collected.

CREATE TABLE submissions (
    id           INTEGER PRIMARY KEY,
    sweep_id     INTEGER NOT NULL REFERENCES sweeps (id) ON DELETE CASCADE,
    dir          TEXT NOT NULL,          -- the sweep directory (specs/, results/, arrays/, logs/)
    script       TEXT NOT NULL,          -- the sbatch script file
    slurm_job    TEXT,                   -- the array's job id from sbatch; NULL until it answered
    tasks        INTEGER NOT NULL,       -- array tasks 0 .. tasks - 1
    submitted_at REAL NOT NULL
);
CREATE INDEX submissions_sweep ON submissions (sweep_id);

CREATE TABLE submission_tasks (
    submission_id INTEGER NOT NULL REFERENCES submissions (id) ON DELETE CASCADE,
    task          INTEGER NOT NULL,      -- SLURM_ARRAY_TASK_ID
    job_id        TEXT NOT NULL REFERENCES jobs (id),
    state         TEXT NOT NULL DEFAULT 'submitted'
                  CHECK (state IN ('submitted', 'collected', 'duplicate', 'failed', 'missing',
                                   'corrupt')),
    message       TEXT,                  -- why failed, missing or corrupt
    PRIMARY KEY (submission_id, task)
);
CREATE INDEX submission_tasks_job ON submission_tasks (job_id);
