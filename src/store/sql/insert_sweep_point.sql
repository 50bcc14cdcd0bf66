-- Adds a job to a sweep's point list.
-- ?1: sweep id, ?2: point, ?3: replica, ?4: coords (JSON), ?5: job id
INSERT INTO sweep_points (sweep_id, point, replica, coords, job_id)
VALUES (?1, ?2, ?3, ?4, ?5)
