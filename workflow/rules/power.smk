# `snakemake --cores all power`: simulated power of H1-H3 (docs/power.md). For each
# variant of power.variants and each replicate r of power.replicates, the simulated
# study with its own seed (casa_core.experiments.power.replicate_seed) and as many participants as
# the largest N of power.sizes; its study of N is its first N participants. A replicate's
# participants are one job, the robustness target's (casa simulate protocol of each in
# turn), so that it pays one process's start-up rather than one a participant; the
# replicates spread over the cores or a cluster. Logs, intents and the
# steps table are temporary: a replicate keeps its trials.csv and detections.csv. Not
# part of the default target.
use rule robustness_participants as power_participants with:
    input:
        config=replicate_config_input,
        scene=power_scene_input,
        population=OPERATOR_POPULATION,
    output:
        before=temp(
            directory(
                expand(
                    REPLICATE / "raw" / "p{p}" / "before",
                    p=POWER_PARTICIPANTS,
                    allow_missing=True,
                )
            )
        ),
        after=temp(
            directory(
                expand(
                    REPLICATE / "raw" / "p{p}" / "after",
                    p=POWER_PARTICIPANTS,
                    allow_missing=True,
                )
            )
        ),
        libraries=temp(
            directory(
                expand(
                    REPLICATE / "intents" / "p{p}" / "{task}",
                    p=POWER_PARTICIPANTS,
                    task=UNKNOWN_TASKS,
                    allow_missing=True,
                )
            )
        ),
        rows=expand(
            REPLICATE / "learning" / "p{p}_{task}.csv",
            p=POWER_PARTICIPANTS,
            task=UNKNOWN_TASKS,
            allow_missing=True,
        ),
        timings=expand(
            REPLICATE / "learning" / "p{p}_{task}_timing.csv",
            p=POWER_PARTICIPANTS,
            task=UNKNOWN_TASKS,
            allow_missing=True,
        ),
    log:
        f"{REPLICATE_LOGS}/participants.log",
    benchmark:
        REPLICATE_BENCHMARKS / "participants.tsv"
    params:
        participants=" ".join(map(str, POWER_PARTICIPANTS)),
        before=participant_path(REPLICATE, "raw", "p{p}", "before"),
        after=participant_path(REPLICATE, "raw", "p{p}", "after"),
        library=participant_path(REPLICATE, "intents", "p{p}"),
        rows=participant_paths(
            REPLICATE, *(f"learning/p{{p}}_{task}.csv" for task in UNKNOWN_TASKS)
        ),
        timings=participant_paths(
            REPLICATE, *(f"learning/p{{p}}_{task}_timing.csv" for task in UNKNOWN_TASKS)
        ),


use rule robustness_process as power_process with:
    input:
        logs=expand(
            REPLICATE / "raw" / "p{p}" / "{stage}",
            p=POWER_PARTICIPANTS,
            stage=("before", "after"),
            allow_missing=True,
        ),
        scene=power_scene_input,
    output:
        trials=REPLICATE / "trials.csv",
        steps=temp(REPLICATE / "steps.csv"),
        likert=temp(REPLICATE / "likert.csv"),
    log:
        f"{REPLICATE_LOGS}/process.log",
    benchmark:
        REPLICATE_BENCHMARKS / "process.tsv"
    params:
        raw=lambda wildcards: POWER_INTERIM / wildcards.variant / f"r{wildcards.r}" / "raw",
        out=lambda wildcards: POWER_INTERIM / wildcards.variant / f"r{wildcards.r}",


# Per N of power.sizes, whether the replicate's first N participants detect each of
# H1-H3 on each metric, in the paper's form and within subjects (casa_core.stats.power).
rule power_detect:
    input:
        trials=REPLICATE / "trials.csv",
        config=replicate_config_input,
    output:
        REPLICATE / "detections.csv",
    log:
        f"{REPLICATE_LOGS}/detect.log",
    benchmark:
        REPLICATE_BENCHMARKS / "detect.tsv"
    conda:
        "../envs/casa.yaml"
    params:
        sizes=" ".join(map(str, POWER_SIZES)),
    shell:
        "exec casa power detect --config {input.config} --trials {input.trials} "
        "--variant {wildcards.variant} --replicate {wildcards.r} --sizes {params.sizes} "
        "--out {output} > {log} 2>&1"


# After each replicate, a line of progress (replicates done, time per replicate, time
# left), printed beside Snakemake's own and appended to data/processed/power/progress.log;
# on the machine running Snakemake, so that the line shows there.
localrules:
    power_progress,


rule power_progress:
    input:
        REPLICATE / "detections.csv",
    output:
        REPLICATE / "progress.txt",
    log:
        f"{REPLICATE_LOGS}/progress.log",
    conda:
        "../envs/casa.yaml"
    params:
        config=CONFIG_FILE,
        log=POWER / "progress.log",
    shell:
        "exec casa progress power --config {params.config} "
        "--done {wildcards.variant}/r{wildcards.r} --out {output} --append {params.log} "
        "2> {log}"


rule power_table:
    input:
        expand(REPLICATE / "detections.csv", variant=POWER_VARIANTS, r=POWER_REPLICATES),
    output:
        POWER / "power.csv",
    log:
        "logs/power/table.log",
    conda:
        "../envs/casa.yaml"
    params:
        population=shlex.quote(population_label(config["simulation"])),
    shell:
        "exec casa power table --detections {input} --population {params.population} "
        "--out {output} > {log} 2>&1"


rule power_figure:
    input:
        power=POWER / "power.csv",
        config=CONFIG_FILE,
    output:
        pdf=FIGURES / "power.pdf",
        png=FIGURES / "power.png",
    log:
        "logs/power/figure.log",
    conda:
        "../envs/casa.yaml"
    params:
        stem=FIGURES / "power",
        provenance=provenance_options,
    shell:
        "exec casa power figure --power {input.power} {params.provenance} "
        "--out {params.stem} > {log} 2>&1"


rule power:
    input:
        rules.power_table.output,
        rules.power_figure.output,
        expand(REPLICATE / "progress.txt", variant=POWER_VARIANTS, r=POWER_REPLICATES),
