-- Runs that are not repeated (docs/service.md, "Cache"): the canonical scene hash of every
-- job (indexed: a submission looks up completed jobs by it) and, for a job answered from a
-- completed one, that job's id (`cached_from`; its rows and files are served from there).
-- Not a foreign key, like `rerun_of`.
ALTER TABLE jobs ADD COLUMN scene_hash TEXT;
ALTER TABLE jobs ADD COLUMN cached_from TEXT;
-- Jobs stored before this migration: a finished run's summary carries its scene hash.
UPDATE jobs SET scene_hash = json_extract(summary, '$.scene_hash') WHERE summary IS NOT NULL;
CREATE INDEX jobs_scene_hash ON jobs (scene_hash);
