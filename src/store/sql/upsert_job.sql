-- Inserts a job, or gives an existing one its new spec (same id: other thresholds).
-- ?1: job id, ?2: spec (canonical JSON), ?3: created at, ?4: predecessor job id (the spec's
-- start_from; NULL for none)
INSERT INTO jobs (id, spec, created_at, start_from) VALUES (?1, ?2, ?3, ?4)
ON CONFLICT (id) DO UPDATE SET spec = excluded.spec, start_from = excluded.start_from
