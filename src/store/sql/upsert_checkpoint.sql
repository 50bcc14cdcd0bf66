-- Stores (replacing) a job's checkpoint.
-- ?1: job id, ?2: state time, ?3: state (JSON), ?4: created at
INSERT OR REPLACE INTO checkpoints (job_id, time, state, created_at)
VALUES (?1, ?2, ?3, ?4)
