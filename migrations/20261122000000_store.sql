-- The wetgran store: sweeps, content-addressed jobs, the grid points that link them, results,
-- and one row per attempt to run a job (the audit trail that shows no job ran twice).
-- Times are seconds since the Unix epoch (REAL).

CREATE TABLE meta (
    key   TEXT PRIMARY KEY,
    value TEXT NOT NULL
);
INSERT INTO meta (key, value) VALUES ('application', 'wetgran');

CREATE TABLE sweeps (
    id          INTEGER PRIMARY KEY,
    name        TEXT NOT NULL UNIQUE,
    file        TEXT NOT NULL,           -- the sweep file as given when last registered
    source      TEXT NOT NULL,           -- its text
    description TEXT,
    cost        TEXT,                    -- the file's cost note for long runs
    axes        TEXT NOT NULL,           -- JSON: [{name, key, label, kind, values}]
    replicas    INTEGER NOT NULL,
    created_at  REAL NOT NULL,
    updated_at  REAL NOT NULL
);

CREATE TABLE jobs (
    id           TEXT PRIMARY KEY,       -- SHA-256 of the canonical spec
    spec         TEXT NOT NULL,          -- canonical JSON
    status       TEXT NOT NULL DEFAULT 'pending'
                 CHECK (status IN ('pending', 'running', 'done', 'failed')),
    attempts     INTEGER NOT NULL DEFAULT 0,   -- times the job was claimed
    owner        TEXT,                   -- host:pid:nonce of the runner holding it
    heartbeat    REAL,                   -- last sign of life of that runner for this job
    claimed_at   REAL,
    finished_at  REAL,
    wall_seconds REAL,                   -- of the last attempt that ended (done or failed)
    last_error   TEXT,
    created_at   REAL NOT NULL
);
CREATE INDEX jobs_status ON jobs (status);

CREATE TABLE sweep_points (
    sweep_id INTEGER NOT NULL REFERENCES sweeps (id) ON DELETE CASCADE,
    point    INTEGER NOT NULL,           -- row-major grid index, last axis fastest
    replica  INTEGER NOT NULL,
    coords   TEXT NOT NULL,              -- JSON array of the axis values
    job_id   TEXT NOT NULL REFERENCES jobs (id),
    PRIMARY KEY (sweep_id, point, replica)
);
CREATE INDEX sweep_points_job ON sweep_points (job_id);

CREATE TABLE results (
    job_id         TEXT PRIMARY KEY REFERENCES jobs (id),
    phase          TEXT,                 -- s, f, g, sfc, sgc, fgc; NULL until classified
    decided_on     TEXT,                 -- JSON: the numbers and thresholds behind the phase
    observables    TEXT NOT NULL,        -- JSON
    simulated_time REAL NOT NULL,
    wall_seconds   REAL NOT NULL,
    events         INTEGER NOT NULL,
    owner          TEXT NOT NULL,
    finished_at    REAL NOT NULL
);

CREATE TABLE runs (
    id         INTEGER PRIMARY KEY,
    job_id     TEXT NOT NULL REFERENCES jobs (id),
    owner      TEXT NOT NULL,
    started_at REAL NOT NULL,
    ended_at   REAL,
    outcome    TEXT                      -- done, failed, discarded; NULL: the runner died
);
CREATE INDEX runs_job ON runs (job_id);
