-- Opens a run row for a claimed job; returns its id.
-- ?1: job id, ?2: owner, ?3: started at
INSERT INTO runs (job_id, owner, started_at) VALUES (?1, ?2, ?3) RETURNING id
