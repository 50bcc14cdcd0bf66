-- Marks the merged job done with the times of the job whose result it took (re-keying).
-- ?1: old job id (whose result moved), ?2: new job id
UPDATE jobs SET status = 'done',
    finished_at = (SELECT finished_at FROM jobs WHERE id = ?1),
    wall_seconds = (SELECT wall_seconds FROM jobs WHERE id = ?1),
    last_error = NULL
WHERE id = ?2
