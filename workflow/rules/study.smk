# The simulated study (paper, Sec. V), learning, and the expert case study (Sec. IV).
# One job per participant (its whole protocol), so that --cores 2 keeps both busy.
# The simulated study is the dataset data/raw/simulated; .complete marks it done. Each
# participant's learned intents are kept in its folder (p<N>/intents/<task>/), as a
# dataset keeps the intents its trials ran with (docs/data-contracts.md).

PARTICIPANTS = list(range(1, config["simulation"]["participants"] + 1))
SIMULATED = RAW / SIMULATED_NAME


wildcard_constraints:
    p=r"\d+",
    task="|".join(UNKNOWN_TASKS),


# Each participant's whole protocol is one job (casa simulate protocol: before learning,
# learning each unknown task's intent, after learning), so that each participant pays one
# job's start-up; the robustness and power targets run a variant's or a replicate's
# participants in one job of the same command (robustness.smk).
rule simulated_participant:
    input:
        config=CONFIG_FILE,
        scene=config["scene"],
        population=OPERATOR_POPULATION,
    output:
        before=directory(SIMULATED / "p{p}" / "before"),
        after=directory(SIMULATED / "p{p}" / "after"),
        libraries=directory(
            expand(
                SIMULATED / "p{p}" / "intents" / "{task}", task=UNKNOWN_TASKS, allow_missing=True
            )
        ),
        rows=expand(
            PROCESSED / "simulated" / "learning" / "p{p}_{task}.csv",
            task=UNKNOWN_TASKS,
            allow_missing=True,
        ),
        timings=expand(
            PROCESSED / "simulated" / "learning" / "p{p}_{task}_timing.csv",
            task=UNKNOWN_TASKS,
            allow_missing=True,
        ),
    log:
        "logs/simulate/p{p}_protocol.log",
    conda:
        "../envs/casa.yaml"
    params:
        # The folder of the participant's libraries, one per unknown task.
        library=lambda wildcards, output: Path(output.libraries[0]).parent,
    shell:
        "exec casa simulate protocol --config {input.config} --participant {wildcards.p} "
        "--before {output.before} --library {params.library} --rows {output.rows} "
        "--timing-rows {output.timings} --out {output.after} > {log} 2>&1"


rule learning_table:
    input:
        rows=expand(
            PROCESSED / "simulated" / "learning" / "p{p}_{task}.csv",
            p=PARTICIPANTS,
            task=UNKNOWN_TASKS,
        ),
        timing=expand(
            PROCESSED / "simulated" / "learning" / "p{p}_{task}_timing.csv",
            p=PARTICIPANTS,
            task=UNKNOWN_TASKS,
        ),
    output:
        table=PROCESSED / "simulated" / "learning.csv",
        timing=PROCESSED / "simulated" / "learning_timing.csv",
    log:
        "logs/simulate/learning_table.log",
    conda:
        "../envs/casa.yaml"
    shell:
        "exec casa simulate learning-table --rows {input.rows} --out {output.table} "
        "--timing-rows {input.timing} --timing {output.timing} > {log} 2>&1"


rule simulated_study:
    input:
        expand(SIMULATED / "p{p}" / "after", p=PARTICIPANTS),
        PROCESSED / "simulated" / "learning.csv",
    output:
        touch(SIMULATED / ".complete"),
    log:
        "logs/simulate/complete.log",


rule case_study:
    input:
        config=CONFIG_FILE,
        scene=config["scene"],
    output:
        steps=PROCESSED / "case_study" / "steps.csv",
        arbitration=PROCESSED / "case_study" / "arbitration.csv",
        work=directory("data/interim/case_study"),
    log:
        "logs/case_study.log",
    conda:
        "../envs/casa.yaml"
    shell:
        "exec casa case-study --config {input.config} --work {output.work} "
        "--steps {output.steps} --arbitration {output.arbitration} > {log} 2>&1"
