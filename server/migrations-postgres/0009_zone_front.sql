-- A cohesive interface's process-zone front (SQLite's 0009_zone_front.sql): extra
-- crack_tips columns at the end, NULL for rows written before (read back as NaN).
ALTER TABLE crack_tips ADD COLUMN zone_x DOUBLE PRECISION;
ALTER TABLE crack_tips ADD COLUMN zone_y DOUBLE PRECISION;
