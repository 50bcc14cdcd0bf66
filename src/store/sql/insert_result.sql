-- Inserts a job's result row.
-- ?1: job id, ?2: phase, ?3: decided_on (JSON), ?4: observables (JSON), ?5: simulated time,
-- ?6: wall seconds, ?7: events, ?8: owner, ?9: finished at
INSERT INTO results (job_id, phase, decided_on, observables, simulated_time,
    wall_seconds, events, owner, finished_at)
VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)
