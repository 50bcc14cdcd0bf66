-- Inserts a job's result row; its trend state is read from the observables once, here, and the
-- verdict on its label from the decision (`observe::settling::Verdict`).
-- ?1: job id, ?2: phase, ?3: decided_on (JSON), ?4: observables (JSON), ?5: simulated time,
-- ?6: wall seconds, ?7: events, ?8: owner, ?9: finished at
INSERT INTO results (job_id, phase, decided_on, observables, simulated_time,
    wall_seconds, events, owner, finished_at, trend, verdict)
VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, json_extract(?4, '$.trend.state'),
    json_extract(?3, '$.settling.verdict'))
