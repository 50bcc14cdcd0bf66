-- Inserts the closed run row of an attempt made elsewhere.
-- ?1: job id, ?2: owner, ?3: started at, ?4: ended at, ?5: outcome
INSERT INTO runs (job_id, owner, started_at, ended_at, outcome)
VALUES (?1, ?2, ?3, ?4, ?5)
