-- Inserts a job, or gives an existing one its new spec (same id: other thresholds).
-- ?1: job id, ?2: spec (canonical JSON), ?3: created at
INSERT INTO jobs (id, spec, created_at) VALUES (?1, ?2, ?3)
ON CONFLICT (id) DO UPDATE SET spec = excluded.spec
