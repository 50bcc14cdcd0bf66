-- Checkpoints: the final state of every finished job (`sim::EngineState` as JSON: time,
-- positions, velocities, radii, bridges, event counts, energy ledger), written in the same
-- transaction as its result. `sweep resume --extend` continues unconverged jobs from here, and a
-- continuation sweep starts each point from its predecessor's checkpoint.

CREATE TABLE checkpoints (
    job_id     TEXT PRIMARY KEY REFERENCES jobs (id),
    time       REAL NOT NULL,            -- simulated time of the state
    state      TEXT NOT NULL,            -- JSON EngineState
    created_at REAL NOT NULL
);
