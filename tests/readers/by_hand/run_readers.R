# rGEDI's and ICESat2VegR's user-facing functions on one set of granules (issue 38, item 6).
# Called by run_readers.sh, not by ctest. Usage:
#   Rscript run_readers.R gedi LABEL L1B.h5 L2A.h5 L2B.h5 OUT.tsv SCRATCH_DIR
#   Rscript run_readers.R icesat2 LABEL ATL03.h5 ATL08.h5 OUT.tsv SCRATCH_DIR
# Appends one row a call to OUT.tsv: reader, call, label, result. A result is "works" (and,
# where the call returns a table or a clipped file, it holds rows and its checked columns are
# not all NA or fill), "empty: ...", "all fill: ...", "leaves out ...", or "error: ..." (R's
# message, one line).

suppressPackageStartupMessages({
  library(hdf5r)
  library(data.table)
})

grDevices::pdf(NULL)  # a plot not sent to a PNG below goes nowhere (no Rplots.pdf)
args <- commandArgs(trailingOnly = TRUE)
mode <- args[1]
label <- args[2]

rows <- list()
one_line <- function(s) substr(gsub("[[:space:]]+", " ", s), 1, 400)

# The call that the reader's own code made when an error arose: the innermost frame whose
# caller is a function of rGEDI or ICESat2VegR (hdf5r's messages do not name the path).
failing_call <- function(calls, frames) {
  handler <- which(vapply(calls, function(c) identical(c[[1]], quote(.handleSimpleError)), logical(1)))
  if (length(handler) > 0) {
    calls <- calls[seq_len(handler[1] - 1L)]
    frames <- frames[seq_len(handler[1] - 1L)]
  }
  in_reader <- vapply(frames, function(f) {
    env <- environment(f)
    !is.null(env) && environmentName(topenv(env)) %in% c("rGEDI", "ICESat2VegR")
  }, logical(1))
  k <- max(c(0L, which(in_reader)))
  if (k == 0L || k >= length(calls)) return("")
  paste(deparse(calls[[k + 1L]], width.cutoff = 500L), collapse = " ")
}

# An HDF5 error stack in one line: its last error's text.
short_message <- function(msg) {
  if (!grepl("^HDF5-API Errors", msg)) return(msg)
  lines <- regmatches(msg, gregexpr("error #[0-9]+: [^\n]*", msg))[[1]]
  paste("HDF5:", sub(".*line [0-9]+: ", "", lines[length(lines)]))
}

# Evaluates a call; returns its value (NULL on error) and records the row. `check` takes the
# value and returns NULL when it is sound, else the problem in words.
record <- function(reader, name, expr, check = NULL) {
  env <- parent.frame()
  call <- substitute(expr)
  where <- ""
  value <- tryCatch(
    withCallingHandlers(eval(call, env),
      warning = function(w) invokeRestart("muffleWarning"),
      error = function(e) {
        n <- sys.nframe()
        where <<- failing_call(sys.calls(), lapply(seq_len(n), sys.function))
      }),
    error = function(e) structure(conditionMessage(e), class = "reader_error")
  )
  if (inherits(value, "reader_error")) {
    result <- paste("error:", short_message(value))
    if (nzchar(where)) result <- paste0(result, " [at ", where, "]")
    value <- NULL
  } else {
    problem <- if (is.null(check)) NULL else tryCatch(check(value),
      error = function(e) paste("check failed:", conditionMessage(e)))
    result <- if (is.null(problem)) "works" else problem
  }
  rows[[length(rows) + 1]] <<- data.frame(reader = reader, call = name, label = label,
                                          result = one_line(result))
  invisible(value)
}

is_fill <- function(x) {
  if (!is.numeric(x)) return(is.na(x))
  is.na(x) | x == -9999 | abs(x) > 1e30 | x == 32767 | x == 65535 | x == 127
}

# A table with rows whose `cols` are not all fill; cols absent are reported.
table_check <- function(cols = character(0), expect_all = TRUE) {
  function(v) {
    if (is.null(v) || NROW(v) == 0) return("empty: no rows")
    missing <- setdiff(cols, names(v))
    if (expect_all && length(missing) > 0)
      return(paste("leaves out", paste(missing, collapse = ", ")))
    fill <- Filter(function(c) all(is_fill(v[[c]])), intersect(cols, names(v)))
    if (length(fill) > 0) return(paste("all fill:", paste(fill, collapse = ", ")))
    NULL
  }
}

plot_to <- function(scratch, name) grDevices::png(file.path(scratch, paste0(name, ".png")))

two_halves <- function(lon, lat) {
  # Two rectangles splitting the data's latitudes at their median, id 1 (south) and 2.
  ok <- is.finite(lon) & is.finite(lat) & abs(lat) <= 90
  lon <- lon[ok]; lat <- lat[ok]
  pad <- 1e-4
  x0 <- min(lon) - pad; x1 <- max(lon) + pad
  y0 <- min(lat) - pad; y1 <- max(lat) + pad; ym <- stats::median(lat)
  rect <- function(a, b) sf::st_polygon(list(rbind(c(x0, a), c(x1, a), c(x1, b), c(x0, b), c(x0, a))))
  polys <- sf::st_sf(id = c(1L, 2L), geometry = sf::st_sfc(rect(y0, ym), rect(ym, y1), crs = 4326))
  list(xmin = x0, xmax = x1, ymin = y0, ymax = ym, polys = polys)
}

h5_column <- function(file, pattern, path) {
  f <- H5File$new(file, mode = "r")
  on.exit(f$close_all())
  groups <- grep(pattern, names(f), value = TRUE)
  unlist(lapply(groups, function(g) if (f$exists(paste0(g, "/", path))) f[[paste0(g, "/", path)]][] else NULL))
}

run_gedi <- function(l1b_file, l2a_file, l2b_file, scratch) {
  suppressPackageStartupMessages(library(rGEDI))
  lon <- h5_column(l2a_file, "^BEAM", "lon_lowestmode")
  lat <- h5_column(l2a_file, "^BEAM", "lat_lowestmode")
  box <- two_halves(lon, lat)
  R <- "rGEDI"

  l1b <- record(R, "readLevel1B", readLevel1B(l1b_file),
                function(v) if (!inherits(v, "gedi.level1b")) "not a gedi.level1b")
  geo <- record(R, "getLevel1BGeo", getLevel1BGeo(l1b),
                table_check(c("shot_number", "latitude_bin0", "longitude_bin0", "elevation_bin0",
                              "elevation_lastbin")))
  shot <- if (!is.null(geo)) as.character(geo$shot_number[1]) else NA
  wf <- record(R, "getLevel1BWF", getLevel1BWF(l1b, shot_number = shot),
               function(v) {
                 d <- v@dt
                 if (nrow(d) == 0) return("empty: no samples")
                 if (all(d$rxwaveform == d$rxwaveform[1])) return("all fill: rxwaveform flat")
                 NULL
               })
  plot_to(scratch, "wf")
  record(R, "plot(gedi.fullwaveform, relative=FALSE, polygon=TRUE)",
         plot(wf, relative = FALSE, polygon = TRUE, type = "l"))
  record(R, "plot(gedi.fullwaveform, relative=TRUE)", plot(wf, relative = TRUE, type = "l"))
  grDevices::dev.off()

  l2a <- record(R, "readLevel2A", readLevel2A(l2a_file),
                function(v) if (!inherits(v, "gedi.level2a")) "not a gedi.level2a")
  am <- record(R, "getLevel2AM", getLevel2AM(l2a),
               table_check(c("shot_number", "lat_lowestmode", "lon_lowestmode", "elev_lowestmode",
                             "elev_highestreturn", "rh50", "rh98", "rh100")))
  plot_to(scratch, "wfmetrics")
  record(R, "plotWFMetrics", plotWFMetrics(l1b, l2a, shot, rh = c(25, 50, 75, 90)))
  grDevices::dev.off()

  l2b <- record(R, "readLevel2B", readLevel2B(l2b_file),
                function(v) if (!inherits(v, "gedi.level2b")) "not a gedi.level2b")
  vpm <- record(R, "getLevel2BVPM", getLevel2BVPM(l2b),
                table_check(c("shot_number", "latitude_lastbin", "longitude_lastbin", "pai",
                              "cover", "fhd_normal", "pgap_theta", "rh100")))
  pai <- record(R, "getLevel2BPAIProfile", getLevel2BPAIProfile(l2b),
                table_check(c("shot_number", "lat_lowestmode", "lon_lowestmode", "pai_z0_5m")))
  pavd <- record(R, "getLevel2BPAVDProfile", getLevel2BPAVDProfile(l2b),
                 table_check(c("shot_number", "lat_lowestmode", "lon_lowestmode", "pavd_z0_5m")))
  beam <- if (!is.null(pai)) as.character(pai$beam[1]) else "BEAM0101"
  plot_to(scratch, "profiles")
  record(R, "plotPAIProfile", print(plotPAIProfile(pai, beam = beam, elev = TRUE)))
  record(R, "plotPAVDProfile", print(plotPAVDProfile(pavd, beam = beam, elev = TRUE)))
  grDevices::dev.off()

  # Clipping: the southern half by a box, both halves by polygons (split by id).
  clipped_rows <- function(get) function(v) {
    n <- tryCatch(nrow(get(v)), error = function(e) NA)
    if (is.na(n) || n == 0) "empty: the clipped file has no shots" else NULL
  }
  outfile <- function(n) file.path(scratch, paste0(n, ".h5"))
  record(R, "clipLevel1B", clipLevel1B(l1b, box$xmin, box$xmax, box$ymin, box$ymax,
                                       output = outfile("l1b_bb")),
         clipped_rows(getLevel1BGeo))
  record(R, "clipLevel2A", clipLevel2A(l2a, box$xmin, box$xmax, box$ymin, box$ymax,
                                       output = outfile("l2a_bb")),
         clipped_rows(getLevel2AM))
  record(R, "clipLevel2B", clipLevel2B(l2b, box$xmin, box$xmax, box$ymin, box$ymax,
                                       output = outfile("l2b_bb")),
         clipped_rows(getLevel2BVPM))
  first <- function(get) function(v) clipped_rows(get)(v[[1]])
  record(R, "clipLevel1BGeometry", clipLevel1BGeometry(l1b, box$polys, output = outfile("l1b_gb"),
                                                       split_by = "id"), first(getLevel1BGeo))
  record(R, "clipLevel2AGeometry", clipLevel2AGeometry(l2a, box$polys, output = outfile("l2a_gb"),
                                                       split_by = "id"), first(getLevel2AM))
  record(R, "clipLevel2BGeometry", clipLevel2BGeometry(l2b, box$polys, output = outfile("l2b_gb"),
                                                       split_by = "id"), first(getLevel2BVPM))
  nonempty <- table_check()
  record(R, "clipLevel1BGeo", clipLevel1BGeo(geo, box$xmin, box$xmax, box$ymin, box$ymax), nonempty)
  record(R, "clipLevel2AM", clipLevel2AM(am, box$xmin, box$xmax, box$ymin, box$ymax), nonempty)
  record(R, "clipLevel2BVPM", clipLevel2BVPM(vpm, box$xmin, box$xmax, box$ymin, box$ymax), nonempty)
  record(R, "clipLevel2BPAIProfile",
         clipLevel2BPAIProfile(pai, box$xmin, box$xmax, box$ymin, box$ymax), nonempty)
  record(R, "clipLevel2BPAVDProfile",
         clipLevel2BPAVDProfile(pavd, box$xmin, box$xmax, box$ymin, box$ymax), nonempty)
  record(R, "clipLevel1BGeoGeometry", clipLevel1BGeoGeometry(geo, box$polys, split_by = "id"), nonempty)
  am_gb <- record(R, "clipLevel2AMGeometry", clipLevel2AMGeometry(am, box$polys, split_by = "id"),
                  nonempty)
  vpm_gb <- record(R, "clipLevel2BVPMGeometry", clipLevel2BVPMGeometry(vpm, box$polys, split_by = "id"),
                   nonempty)
  record(R, "clipLevel2BPAIProfileGeometry",
         clipLevel2BPAIProfileGeometry(pai, box$polys, split_by = "id"), nonempty)
  record(R, "clipLevel2BPAVDProfileGeometry",
         clipLevel2BPAVDProfileGeometry(pavd, box$polys, split_by = "id"), nonempty)

  stats4 <- function(x) list(min = min(x), max = max(x), mean = mean(x), sd = sd(x))
  record(R, "polyStatsLevel2AM", polyStatsLevel2AM(am_gb, func = max(rh100), id = "poly_id"),
         table_check("max"))
  record(R, "polyStatsLevel2BVPM", polyStatsLevel2BVPM(vpm_gb, func = stats4(cover), id = "poly_id"),
         table_check("mean"))
  grid_check <- function(v) {
    vals <- terra::values(if (inherits(v, "SpatRaster")) v else terra::rast(v))
    if (all(is.na(vals))) "all fill: every cell NA" else NULL
  }
  record(R, "gridStatsLevel2AM", gridStatsLevel2AM(am, func = stats4(rh100), res = 0.001), grid_check)
  record(R, "gridStatsLevel2BVPM", gridStatsLevel2BVPM(vpm, func = stats4(pai), res = 0.001), grid_check)
}

run_icesat2 <- function(atl03_file, atl08_file, scratch) {
  suppressPackageStartupMessages({
    library(ICESat2VegR)
    library(terra)
  })
  lon <- h5_column(atl08_file, "^gt[1-3][lr]$", "land_segments/longitude")
  lat <- h5_column(atl08_file, "^gt[1-3][lr]$", "land_segments/latitude")
  box <- two_halves(lon, lat)
  ext <- terra::ext(box$xmin, box$xmax, box$ymin, box$ymax)
  polys <- terra::vect(box$polys)
  R <- "ICESat2VegR"
  outfile <- function(n) file.path(scratch, paste0(n, ".h5"))
  # The LAS writers put the UTM zone's EPSG code in the name: NAME_326ZZ.las.
  las_check <- function(n) function(v) {
    if (length(list.files(scratch, paste0("^", n, ".*\\.las$"))) == 0) "empty: no LAS file" else NULL
  }

  atl03 <- record(R, "ATL03_read", ATL03_read(atl03_file), function(v) {
    so <- v[["orbit_info/sc_orient"]][]
    # The data dictionary's strong beams: the left ones backward (0), the right ones forward.
    want <- grep(if (so == 0) "l$" else "r$", v$beams, value = TRUE)
    if (!setequal(v$strong_beams, want))
      return(paste0("strong beams '", paste(v$strong_beams, collapse = " "), "' for sc_orient ", so))
    NULL
  })
  atl08 <- record(R, "ATL08_read", ATL08_read(atl08_file),
                  function(v) if (length(v$beams) == 0) "empty: no beams")
  record(R, "rgt_extract", rgt_extract(atl03, line = TRUE),
         function(v) if (NROW(v) == 0) "empty: no geometry")

  ph <- record(R, "ATL03_photons_attributes_dt", ATL03_photons_attributes_dt(atl03),
               table_check(c("lon_ph", "lat_ph", "h_ph", "quality_ph", "dist_ph_along")))
  seg_defaults <- eval(formals(ICESat2VegR::ATL03_seg_metadata_dt)$attributes)
  seg <- record(R, "ATL03_seg_metadata_dt (its 34 default fields)", ATL03_seg_metadata_dt(atl03),
                table_check(seg_defaults))
  seg2 <- record(R, "ATL03_seg_metadata_dt (README's delta_time, solar_elevation, h_ph, ref_elev, + segment_dist_x)",
                 ATL03_seg_metadata_dt(atl03, attributes = c("delta_time", "solar_elevation",
                                                             "h_ph", "ref_elev",
                                                             "segment_dist_x")),
                 table_check(c("delta_time", "solar_elevation", "h_ph", "ref_elev",
                               "segment_dist_x")))
  plot_to(scratch, "atl03_seg")
  record(R, "plot(icesat2.atl03_seg_dt)", plot(seg2))
  grDevices::dev.off()

  l08 <- record(R, "ATL08_seg_attributes_dt (defaults)", ATL08_seg_attributes_dt(atl08),
                table_check(c("latitude", "longitude", "h_canopy", "canopy_openness",
                              "h_te_mean", "terrain_slope")))
  record(R, "ATL08_seg_attributes_dt (README's, with night_flag)",
         ATL08_seg_attributes_dt(atl08, attributes = c("h_canopy", "h_te_mean", "terrain_slope",
                                                       "canopy_openness", "night_flag")),
         table_check(c("h_canopy", "h_te_mean", "terrain_slope", "canopy_openness", "night_flag")))
  more <- c("h_te_mode", "h_te_std", "toc_roughness", "segment_cover", "h_median_canopy",
            "h_min_canopy", "h_max_canopy", "h_te_median", "h_te_max")
  record(R, "ATL08_seg_attributes_dt (h_te_mode, h_te_std, toc_roughness, segment_cover, h_te_median, ...)",
         ATL08_seg_attributes_dt(atl08, attributes = more), table_check(more))
  record(R, "ATL08_seg_attributes_dt (h_te_min: not in its name map)",
         ATL08_seg_attributes_dt(atl08, attributes = "h_te_min"), table_check("h_te_min"))
  record(R, "ATL08_seg_attributes_dt (canopy_rh_conf)",
         ATL08_seg_attributes_dt(atl08, attributes = "canopy_rh_conf"),
         table_check("canopy_rh_conf"))
  l08p <- record(R, "ATL08_photons_attributes_dt", ATL08_photons_attributes_dt(atl08),
                 table_check(c("ph_segment_id", "classed_pc_indx", "classed_pc_flag", "ph_h")))

  join <- record(R, "ATL03_ATL08_photons_attributes_dt_join",
                 ATL03_ATL08_photons_attributes_dt_join(atl03, atl08),
                 table_check(c("lon_ph", "lat_ph", "h_ph", "classed_pc_flag", "ph_h")))
  beam <- if (!is.null(join)) as.character(join$beam[1]) else "gt2l"
  plot_to(scratch, "join")
  record(R, "plot(icesat2.atl03atl08_dt, y = \"h_ph\")", plot(join, y = "h_ph", beam = beam))
  record(R, "plot(icesat2.atl03atl08_dt, y = \"ph_h\")",
         plot(join, y = "ph_h", beam = beam, legend = FALSE))
  grDevices::dev.off()
  raster_check <- function(v) if (all(is.na(terra::values(v)))) "all fill: every cell NA" else NULL
  record(R, "ATL03_ATL08_photons_attributes_dt_gridStat",
         ATL03_ATL08_photons_attributes_dt_gridStat(join, func = list(h98 = quantile(ph_h, 0.98),
                                                                      n = .N),
                                                    res = 0.0005, night_flag = c(0, 1)),
         raster_check)
  record(R, "ATL03_ATL08_photons_attributes_dt_clipBox",
         ATL03_ATL08_photons_attributes_dt_clipBox(join, ext), table_check("h_ph"))
  jgb <- record(R, "ATL03_ATL08_photons_attributes_dt_clipGeometry",
                ATL03_ATL08_photons_attributes_dt_clipGeometry(join, polys, split_by = "id"),
                table_check("h_ph"))
  record(R, "ATL03_ATL08_photons_attributes_dt_polyStat",
         ATL03_ATL08_photons_attributes_dt_polyStat(jgb, func = list(n = .N, h = mean(h_ph)),
                                                    poly_id = "poly_id"),
         table_check("n"))
  record(R, "ATL03_ATL08_photons_attributes_dt_LAS",
         ATL03_ATL08_photons_attributes_dt_LAS(join, file.path(scratch, "join.las")),
         las_check("join"))
  segs <- record(R, "ATL03_ATL08_segment_create (30 m)",
                 ATL03_ATL08_segment_create(join, segment_length = 30, centroid = "mean"),
                 table_check("segment_id"))
  seg_stat <- record(R, "ATL03_ATL08_compute_seg_attributes_dt_segStat",
                     ATL03_ATL08_compute_seg_attributes_dt_segStat(segs, list(
                       h98 = quantile(ph_h, 0.98), n_ground = sum(classed_pc_flag == 1),
                       n_canopy = sum(classed_pc_flag >= 2)), ph_class = c(1, 2, 3)),
                     table_check(c("longitude", "latitude", "h98", "n_ground")))
  record(R, "ATL03_ATL08_photons_seg_dt_fitground",
         ATL03_ATL08_photons_seg_dt_fitground(segs, interpolation_func = approx),
         function(v) if (NROW(v) == 0) "empty")
  record(R, "ATL03_ATL08_photons_seg_dt_height_normalize",
         ATL03_ATL08_photons_seg_dt_height_normalize(segs), function(v) if (NROW(v) == 0) "empty")
  record(R, "ATL03_ATL08_seg_attributes_dt_clipBox",
         ATL03_ATL08_seg_attributes_dt_clipBox(seg_stat, ext), table_check("h98"))
  record(R, "ATL03_ATL08_seg_attributes_dt_clipGeometry",
         ATL03_ATL08_seg_attributes_dt_clipGeometry(seg_stat, polys, split_by = "id"),
         table_check("h98"))
  record(R, "ATL03_ATL08_seg_cover_dt_compute",
         ATL03_ATL08_seg_cover_dt_compute(data.table::copy(segs)),
         function(v) if (NROW(v) == 0) "empty")

  h5_clip_check <- function(reader, get) function(v) {
    n <- tryCatch(NROW(get(reader(v$h5$filename))), error = function(e) NA)
    if (is.na(n) || n == 0) "empty: the clipped file reads no rows" else NULL
  }
  record(R, "ATL03_h5_clipBox", ATL03_h5_clipBox(atl03, outfile("atl03_bb"), ext),
         h5_clip_check(ATL03_read, ATL03_photons_attributes_dt))
  record(R, "ATL03_h5_clipGeometry", ATL03_h5_clipGeometry(atl03, outfile("atl03_gb"), polys),
         h5_clip_check(ATL03_read, ATL03_photons_attributes_dt))
  record(R, "ATL08_h5_clipBox", ATL08_h5_clipBox(atl08, outfile("atl08_bb"), ext),
         h5_clip_check(ATL08_read, ATL08_seg_attributes_dt))
  record(R, "ATL08_h5_clipGeometry", ATL08_h5_clipGeometry(atl08, outfile("atl08_gb"), polys),
         h5_clip_check(ATL08_read, ATL08_seg_attributes_dt))
  record(R, "clip(icesat2.atl03_h5, SpatExtent)", clip(atl03, output = outfile("atl03_generic"),
                                                                  clip_obj = ext),
         h5_clip_check(ATL03_read, ATL03_photons_attributes_dt))
  record(R, "clip(icesat2.atl08_dt, SpatVector)", clip(l08, clip_obj = polys), table_check("h_canopy"))

  record(R, "ATL03_photons_attributes_dt_clipBox", ATL03_photons_attributes_dt_clipBox(ph, ext),
         table_check("h_ph"))
  record(R, "ATL03_photons_attributes_dt_clipGeometry",
         ATL03_photons_attributes_dt_clipGeometry(ph, polys, split_by = "id"), table_check("h_ph"))
  record(R, "ATL03_photons_attributes_dt_LAS",
         ATL03_photons_attributes_dt_LAS(ph, file.path(scratch, "atl03.las")),
         las_check("atl03"))
  record(R, "ATL08_photons_attributes_dt_LAS",
         ATL08_photons_attributes_dt_LAS(l08p, file.path(scratch, "atl08_ph.las")),
         las_check("atl08_ph"))
  record(R, "ATL08_seg_attributes_dt_LAS",
         ATL08_seg_attributes_dt_LAS(l08, file.path(scratch, "atl08_seg.las")),
         las_check("atl08_seg"))
  record(R, "ATL08_seg_attributes_dt_clipBox", ATL08_seg_attributes_dt_clipBox(l08, ext),
         table_check("h_canopy"))
  record(R, "ATL08_seg_attributes_dt_clipGeometry",
         ATL08_seg_attributes_dt_clipGeometry(l08, polys, split_by = "id"), table_check("h_canopy"))
  record(R, "ATL08_seg_attributes_dt_gridStat",
         ATL08_seg_attributes_dt_gridStat(l08, func = list(max_h = max(h_canopy), n = .N),
                                          res = 0.001), raster_check)
  record(R, "ATL08_seg_attributes_dt_polyStat",
         ATL08_seg_attributes_dt_polyStat(l08, func = list(n = .N, h = mean(h_canopy))),
         table_check("n"))
  dir08 <- file.path(scratch, "atl08_dir")
  dir.create(dir08, showWarnings = FALSE)
  file.copy(atl08_file, file.path(dir08, "ATL08_glaswave.h5"), overwrite = TRUE)
  record(R, "ATL08_seg_attributes_h5_gridStat (h_canopy; its example's aggregates)",
         ATL08_seg_attributes_h5_gridStat(dir08, metrics = c("h_canopy"),
                                          out_root = file.path(scratch, "grid"),
                                          clip_obj = c(xmin = box$xmin, ymin = box$ymin,
                                                       xmax = box$xmax, ymax = box$ymax),
                                          res = c(0.001, -0.001),
                                          agg_function = ~ data.table(max = max(x), n = length(x)),
                                          agg_join = function(a, b) {
                                            a[is.na(a)] <- 0
                                            data.table(max = pmax(a$max, b$max), n = a$n + b$n)
                                          },
                                          finalizer = list(max = "max")),
         function(v) {
           tifs <- list.files(scratch, "^grid.*\\.tif$", full.names = TRUE)
           if (length(tifs) == 0) "empty: no raster written" else NULL
         })
  record(R, "to_vect(icesat2.atl08_dt)", to_vect(l08),
         function(v) if (nrow(v) == 0) "empty: no features")
  record(R, "to_vect(icesat2.atl03_seg_dt)", to_vect(seg2),
         function(v) if (nrow(v) == 0) "empty: no features")
  if (!is.null(l08)) {
    good <- stats::na.omit(l08[h_canopy < 100])
    model <- randomForest::randomForest(data.frame(h_canopy = c(1, 5, 10, 20)), c(10, 50, 100, 200))
    pred <- record(R, "predict_h5 (randomForest on ATL08 h_canopy)",
                   predict_h5(model, good, file.path(scratch, "pred.h5")),
                   function(v) if (length(v) == 0) "empty: nothing predicted")
    record(R, "rasterize_h5", rasterize_h5(pred, file.path(scratch, "pred.tif"), ext, 0.001),
           function(v) if (!file.exists(file.path(scratch, "pred.tif"))) "empty: no raster")
  }
}

out_tsv <- if (mode == "gedi") args[6] else args[5]
scratch <- if (mode == "gedi") args[7] else args[6]
dir.create(scratch, showWarnings = FALSE, recursive = TRUE)
if (mode == "gedi") {
  run_gedi(args[3], args[4], args[5], scratch)
} else if (mode == "icesat2") {
  run_icesat2(args[3], args[4], scratch)
} else {
  stop("mode is gedi or icesat2, got ", mode)
}
out <- do.call(rbind, rows)
write.table(out, out_tsv, sep = "\t", quote = FALSE, row.names = FALSE,
            col.names = !file.exists(out_tsv), append = file.exists(out_tsv))
